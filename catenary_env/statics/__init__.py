"""Shape-finding: the equilibrium of a catenary hanging exactly as designed."""
