"""The loop-work benchmark's counts (benchmarks/loop_work.py; docs/performance.md, 'A window of spans behind
the pantograph, counted, made and dropped'): a window as wide as the section leaves all the work, and a
narrower one less."""

from __future__ import annotations

import importlib
from pathlib import Path

import pytest

from catenary_env.dynamics.span_modes import passage

ROOT = Path(__file__).resolve().parents[1]
SPANS = 6


@pytest.mark.parametrize("ahead", [False, True])
def test_a_window_as_wide_as_the_section_counts_all_the_work(monkeypatch, ahead):
    pytest.importorskip("numba")
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    loop_work = importlib.import_module("loop_work")
    widths = (0, 1, 2, SPANS)
    loop = loop_work.CountingLoop(widths, ahead)
    monkeypatch.setitem(passage.BACKENDS, "numba", lambda: loop)
    row = loop_work.measure(loop, "benchmark", SPANS, full=False, runs=1)
    assert row[f"window {SPANS}"] == row["multiply-adds"] > 0
    counts = [row[f"window {width}"] for width in widths]
    assert all(a < b for a, b in zip(counts, counts[1:], strict=False))  # each span further adds its work
    # a step advances the pantograph's span and those behind and ahead of it, at most the section
    assert 1.0 <= 1.0 + row["spans behind"] + row["spans ahead"] <= SPANS


def test_a_hold_that_waits_for_causality_counts_less_the_less_it_spares(monkeypatch):
    """A hold with more metres to spare than the section is long holds nothing; with fewer, it holds more
    spans, and only towards the passage's end, where the time left is short."""
    pytest.importorskip("numba")
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    loop_work = importlib.import_module("loop_work")
    margins = (1e6, 100.0, 0.0)
    loop = loop_work.CountingLoop(horizons=margins)
    monkeypatch.setitem(passage.BACKENDS, "numba", lambda: loop)
    row = loop_work.measure(loop, "benchmark", SPANS, full=True, runs=1)
    counts = [row[f"horizon {margin:g}"] for margin in margins]
    assert counts[0] == row["multiply-adds"] > 0
    assert counts[0] > counts[1] > counts[2] > 0
