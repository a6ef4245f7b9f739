"""Finite elements: the mesh of a section (layout), ANCF cables and bars, assembly, the banded solver."""
