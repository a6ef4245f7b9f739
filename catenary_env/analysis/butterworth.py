"""The zero-phase Butterworth low-pass filter of the contact force, in numpy and LAPACK.

What scipy.signal's ``butter(..., output="sos")`` and ``sosfiltfilt`` compute (the same second-order sections
and the same edge treatment: odd extension by three times the filter's taps, each pass started in the steady
state of its first sample), written out so that a process need not import scipy.signal: its import takes some
0.45 s (it loads scipy.stats), a quarter of a command-line evaluation (docs/performance.md, 'Speed'). Each
section's recursion is a banded lower-triangular solve (LAPACK ``dtbtrs``), so the results agree with
scipy.signal's to rounding, not to the bit (``tests/test_butterworth.py``).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack


def butterworth_sections(order: int, cutoff: float, sampling: float) -> np.ndarray:
    """Second-order sections (n, 6) ``[b0, b1, b2, 1, a1, a2]`` of a digital Butterworth low-pass of an
    even ``order``, -3 dB at ``cutoff`` Hz when sampled at ``sampling`` Hz: the analogue prototype's poles,
    pre-warped and mapped by the bilinear transform, the gain in the first section and the poles nearest the
    unit circle in the last (as scipy.signal's ``butter``)."""
    if order < 2 or order % 2:
        raise ValueError(f"order = {order!r}: an even number >= 2")
    if not 0.0 < cutoff < 0.5 * sampling:
        raise ValueError(
            f"cutoff = {cutoff!r}: must lie in (0, {0.5 * sampling:g}) Hz, below half the sampling rate"
        )
    warped = 4.0 * np.tan(np.pi * cutoff / sampling)  # the analogue frequency for a sampling of 2 (scipy's)
    analogue = -np.exp(1j * np.pi * np.arange(-order + 1, order, 2) / (2 * order)) * warped
    poles = (4.0 + analogue) / (4.0 - analogue)
    gain = warped**order * np.real(1.0 / np.prod(4.0 - analogue))
    upper = poles[poles.imag > 0.0]
    upper = upper[np.argsort(np.abs(1.0 - np.abs(upper)))[::-1]]  # the farthest from the unit circle first
    sections = np.zeros((order // 2, 6))
    sections[:, :3] = [1.0, 2.0, 1.0]  # the zeros at z = -1, a pair a section
    sections[:, 3] = 1.0
    sections[:, 4] = -2.0 * upper.real
    sections[:, 5] = np.abs(upper) ** 2
    sections[0, :3] *= gain
    return sections


def zero_phase(sections: np.ndarray, signal: np.ndarray) -> np.ndarray:
    """``signal`` (n,) filtered forward and backward through ``sections`` (:func:`butterworth_sections`), as
    scipy.signal's ``sosfiltfilt`` with its default padding: oddly extended by 3 (2 n_sections + 1) samples at
    each end, each pass started in the steady state of its first sample."""
    signal = np.asarray(signal, dtype=float)
    edge = 3 * (2 * sections.shape[0] + 1)
    if signal.size <= edge:
        raise ValueError(f"signal: {signal.size} samples; the filter needs more than {edge}")
    extended = np.concatenate(
        [2.0 * signal[0] - signal[edge:0:-1], signal, 2.0 * signal[-1] - signal[-2 : -edge - 2 : -1]]
    )
    forward = _cascade(sections, extended)
    backward = _cascade(sections, forward[::-1])
    return backward[::-1][edge:-edge]


def _cascade(sections: np.ndarray, signal: np.ndarray) -> np.ndarray:
    """The signal through each section in turn, each started in the steady state of its first input: the
    section's y[i] + a1 y[i-1] + a2 y[i-2] = b0 x[i] + b1 x[i-1] + b2 x[i-2], the inputs before the first
    x[0] and the outputs x[0] B(1) / A(1), solved as a banded lower-triangular system (LAPACK ``dtbtrs``).
    Section by section, not as one recursion of their products, whose poles near the unit circle would lose
    digits at short time steps."""
    x = signal
    band = np.empty((3, x.size), order="F")  # LAPACK's lower band storage: row k holds A[j + k, j]
    band[0] = 1.0
    for b0, b1, b2, _, a1, a2 in sections:
        rhs = b0 * x
        rhs[1:] += b1 * x[:-1]
        rhs[2:] += b2 * x[:-2]
        past_input = x[0]
        past_output = past_input * (b0 + b1 + b2) / (1.0 + a1 + a2)
        rhs[0] += (b1 + b2) * past_input - (a1 + a2) * past_output
        rhs[1] += b2 * past_input - a2 * past_output
        band[1] = a1
        band[2] = a2
        x, info = lapack.dtbtrs(band, rhs, uplo="L")
        if info != 0:  # pragma: no cover - a unit diagonal is never singular
            raise np.linalg.LinAlgError(f"dtbtrs: info {info}")
    return x
