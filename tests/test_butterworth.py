"""The contact force's low-pass filter (catenary_env.analysis.butterworth): scipy.signal's ``butter`` and
``sosfiltfilt`` to rounding, the filter's own physics (unit gain at rest, -3 dB at the cut-off), and no import
of scipy.signal on the way."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from catenary_env.analysis.butterworth import butterworth_sections, zero_phase
from catenary_env.analysis.statistics import CUTOFF_HZ, FILTER_ORDER, lowpass

signal = pytest.importorskip("scipy.signal")


@pytest.mark.parametrize("order", [2, 4, 6])
@pytest.mark.parametrize("sampling", [200.0, 1000.0, 4000.0, 10000.0])
def test_sections_are_scipys(order: int, sampling: float) -> None:
    cutoff = 22.3
    expected = signal.butter(order, cutoff, btype="low", fs=sampling, output="sos")
    sections = butterworth_sections(order, cutoff, sampling)
    np.testing.assert_allclose(sections, expected, rtol=1e-14, atol=1e-17)


@pytest.mark.parametrize("time_step", [1e-4, 2.5e-4, 1e-3, 5e-3])
def test_zero_phase_is_sosfiltfilt(time_step: float) -> None:
    """A contact-force-like history (N): the same filtered force to 10⁻⁹ N, edges included."""
    rng = np.random.default_rng(3)
    n = int(2.0 / time_step)
    force = 120.0 + 30.0 * np.cumsum(rng.standard_normal(n)) / np.sqrt(n) + 20.0 * rng.standard_normal(n)
    per_pass = CUTOFF_HZ / (np.sqrt(2.0) - 1.0) ** (1.0 / (2 * FILTER_ORDER))
    sections = signal.butter(FILTER_ORDER, per_pass, btype="low", fs=1.0 / time_step, output="sos")
    expected = signal.sosfiltfilt(sections, force)
    np.testing.assert_allclose(lowpass(force, time_step), expected, rtol=0.0, atol=1e-9)


def test_rest_and_cutoff() -> None:
    """A constant force passes unchanged; a sine at the cut-off comes out at 1/√2 of its amplitude (the
    applied, forward-backward filter is -3 dB there), one at twice the cut-off at -41 dB (FILTER_ORDER)."""
    time_step = 1e-3
    t = np.arange(0.0, 4.0, time_step)
    np.testing.assert_allclose(lowpass(np.full(t.size, 157.3), time_step), 157.3, rtol=1e-12)
    middle = slice(t.size // 4, 3 * t.size // 4)  # clear of the ends' transients
    at_cutoff = lowpass(np.sin(2.0 * np.pi * CUTOFF_HZ * t), time_step)
    assert np.max(np.abs(at_cutoff[middle])) == pytest.approx(np.sqrt(0.5), rel=2e-3)
    above = lowpass(np.sin(2.0 * np.pi * 2.0 * CUTOFF_HZ * t), time_step)
    assert 20.0 * np.log10(np.max(np.abs(above[middle]))) == pytest.approx(-41.0, abs=1.0)


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="order = 3"):
        butterworth_sections(3, 20.0, 1000.0)
    with pytest.raises(ValueError, match="cutoff = 600"):
        butterworth_sections(4, 600.0, 1000.0)
    with pytest.raises(ValueError, match="signal: 10 samples"):
        zero_phase(butterworth_sections(4, 20.0, 1000.0), np.ones(10))


def test_filtering_does_not_import_scipy_signal() -> None:
    """scipy.signal's import (some 0.45 s: it loads scipy.stats) is what the filter of our own spares every
    process its first evaluation."""
    code = (
        "import sys, numpy as np\n"
        "from catenary_env.analysis.statistics import lowpass\n"
        "lowpass(np.random.default_rng(0).standard_normal(500), 1e-3)\n"
        "print('scipy.signal' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
