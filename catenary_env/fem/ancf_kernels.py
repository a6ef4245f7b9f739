"""Compiled loop of the cable elements' state (:func:`~catenary_env.fem.ancf.cable_state`), with numba.

The same arithmetic as the numpy code of :func:`~catenary_env.fem.ancf.cable_state`, element by element:
the same scaled coordinates, Gauss points, strains and energy density, the same tables. The numpy code works
on (Gauss points × 2 × elements) arrays and a (G, 2, 2, 2, 2, E) hessian, some forty temporaries and three
matrix products over all elements; here each element's 8 coordinates give its force, stiffness and length
derivative in registers and a few small workspaces, several times faster (docs/performance.md, 'Speed').

The force is the numpy code's to the last bit where the BLAS sums in order with fused multiply-adds, as
OpenBLAS's kernels do on processors that have them (and LLVM contracts only there): the strains and the sum
over Gauss points in that order and contracted (:data:`summed`), every other operation as numpy's, neither
contracted nor reassociated. It has to be: shape-finding's Newton iterations stop at the round-off floor of
the residual (docs/model.md, 'Shape-finding'), a sum of element forces far larger than it, and any other
rounding of the force moves the shape within that floor, and σ by some 1e-9 (the strains summed in another
order did; with the force to the bit, the σ of the studies' designs stay within 5e-11 of the numpy code's,
as before). The tangent, which only steers Newton's steps and the linearisation, is summed in another
order, in two stages per Gauss point: M = ∇²W G (4 × 8, from the hessian's 4 × 4 in the strains
e = (r_s, L r_ss)), then w Gᵀ M, the upper triangle only (the tangent is symmetric), some 140
multiplications a point rather than the 320 of the table of products.

In an evaluation of B1's reference design, cable_state's nine calls take 6.4 ms rather than 12.9 ms; the
tangent's four, 1.1 to 1.2 ms each, are most of it.

numba is optional: :mod:`~catenary_env.fem.ancf` imports this module only where numba is installed.
"""

from __future__ import annotations

import numpy as np
from numba import njit

inlined = njit(cache=True, inline="always")
"""The decorator of the element-wise helpers of one element's Gauss point: inlined into the loop (numba's own
inlining), under its floating-point rules (none: each operation rounded as numpy's)."""

summed = njit(cache=True, fastmath={"contract"})
"""The decorator of the sums that stand for the numpy code's matrix products in the force: fused
multiply-adds in the order of the BLAS. Not inlined by numba, which would compile them under the loop's
rules; LLVM inlines them (they are small) and keeps their licence on their own instructions. The tangent's
sums, larger, are inlined by numba: called, they took the loop from 1.2 to 2.1 ms (B1's section)."""


@njit(cache=True)
def cable_state_in_place(
    q,
    length,
    inverse,
    axial_stiffness,
    bending_stiffness,
    s0,
    force_table,
    axial_material,
    force,
    stiffness,
    dlength,
):  # pragma: no cover - compiled
    """Fill ``force`` (E, 8), and where they have E rows ``stiffness`` (E, 8, 8) and ``dlength`` (E, 8).

    ``q``, ``length``, ``axial_stiffness``, ``bending_stiffness`` as :func:`.ancf.cable_state` (m, m, N,
    N·m²), ``inverse`` the numpy code's 1 / L (``ancf._scale``, a power that differs from 1 / L in the last
    bit for some L), 1/m; ``s0`` the shape functions' table (G, 2, 4) (``ancf._S0``), ``force_table`` its
    Gauss-weighted form (2 G, 4) (``ancf._FORCE_TABLE``). A ``stiffness`` or ``dlength`` with no rows is
    not asked for; the length derivative needs the tangent, which is then computed whether stored or not.
    """
    tangent = stiffness.shape[0] > 0
    derivative = dlength.shape[0] > 0
    scale = np.empty(8)
    qs = np.empty(8)
    f = np.empty(8)  # Σ_g w_g L Gᵀ ∇W in the scaled coordinates
    fb = np.empty(8)  # its bending part, for the length derivative
    h = np.empty((4, 4))  # ∇²W times the L of ds, in the strains (r_s, L r_ss)
    m = np.empty((4, 8))  # ∇²W G
    k = np.zeros((8, 8))  # Σ_g w_g Gᵀ ∇²W G, upper triangle
    for e in range(q.shape[0]):
        L = length[e]
        ea = axial_stiffness[e]
        ei = bending_stiffness[e]
        for c in range(8):  # q̃ = (r_i / L, r'_i, r_j / L, r'_j)
            scale[c] = inverse[e] if c % 4 < 2 else 1.0
            qs[c] = q[e, c] * scale[c]
        f[:] = 0.0
        fb[:] = 0.0
        if tangent or derivative:
            k[:] = 0.0
        for g in range(s0.shape[0]):
            rs0, rs1, ls0, ls1 = _strains(s0, g, qs)
            rss0 = ls0 / L
            rss1 = ls1 / L
            nrm = np.sqrt(rs0 * rs0 + rs1 * rs1)
            eps = nrm - 1.0
            t0 = rs0 / nrm
            t1 = rs1 / nrm
            moment = ei * (rs0 * rss1 - rs1 * rss0)  # EI κ, N·m
            p0, p1 = rss1, -rss0  # dκ/dr_s = J r_ss
            s_0, s_1 = -rs1, rs0  # dκ/dr_ss = Jᵀ r_s
            tension = ea * eps
            b0 = moment * s_0
            b1 = moment * s_1
            # The L of ds = L dξ cancels the 1/L of r_ss.
            _add_force(
                force_table, g, (tension * t0 + moment * p0) * L, (tension * t1 + moment * p1) * L, b0, b1, f
            )
            if derivative:
                _add_force(force_table, g, moment * p0 * L, moment * p1 * L, b0, b1, fb)
            if tangent or derivative:
                material = ea if axial_material else 0.0
                _hessian(h, material, ea * eps / nrm, ei, moment, t0, t1, p0, p1, s_0, s_1, L)
                _add_tangent(s0, force_table, g, h, m, k)
        for c in range(8):
            force[e, c] = f[c] * scale[c]
        if tangent:
            _store_tangent(k, scale, stiffness[e])
        if derivative:
            _store_dlength(k, scale, q[e], force[e], fb, L, dlength[e])


@summed
def _strains(s0, g, qs):  # pragma: no cover - compiled
    """r_s and L r_ss at Gauss point g from the scaled coordinates, as the numpy code's product with _S0."""
    rs0 = rs1 = ls0 = ls1 = 0.0
    for j in range(4):
        rs0 += s0[g, 0, j] * qs[2 * j]
        rs1 += s0[g, 0, j] * qs[2 * j + 1]
        ls0 += s0[g, 1, j] * qs[2 * j]
        ls1 += s0[g, 1, j] * qs[2 * j + 1]
    return rs0, rs1, ls0, ls1


@summed
def _add_force(force_table, g, d0, d1, b0, b1, f):  # pragma: no cover - compiled
    """f += w_g Gᵀ (d, b) at Gauss point g: d = L ∂W/∂r_s, b = ∂W/∂(L r_ss), in the scaled coordinates; the
    numpy code's product with _FORCE_TABLE, term by term in its order."""
    for j in range(4):
        wa = force_table[2 * g, j]
        wb = force_table[2 * g + 1, j]
        f[2 * j] += wa * d0
        f[2 * j] += wb * b0
        f[2 * j + 1] += wa * d1
        f[2 * j + 1] += wb * b1


@inlined
def _hessian(h, material, axial, ei, moment, t0, t1, p0, p1, s_0, s_1, L):  # pragma: no cover - compiled
    """h = ∇²W in the strains (r_s, L r_ss), times the L of ds, as the numpy code's hessian[g]:
    material t tᵀ + axial (I - t tᵀ) + EI p pᵀ on r_s (``axial`` = EA ε / |r_s|), EI p sᵀ + EI κ J across,
    EI s sᵀ on r_ss."""
    c0 = t0 * (material - axial)
    c1 = t1 * (material - axial)
    e0 = p0 * ei
    e1 = p1 * ei
    h[0, 0] = (c0 * t0 + e0 * p0 + axial) * L
    h[0, 1] = (c0 * t1 + e0 * p1) * L
    h[1, 0] = (c1 * t0 + e1 * p0) * L
    h[1, 1] = (c1 * t1 + e1 * p1 + axial) * L
    h[0, 2] = e0 * s_0
    h[0, 3] = e0 * s_1 + moment
    h[1, 2] = e1 * s_0 - moment
    h[1, 3] = e1 * s_1
    for a in range(2):
        for b in range(2):
            h[2 + a, b] = h[b, 2 + a]
    ratio = ei / L
    h[2, 2] = s_0 * ratio * s_0
    h[2, 3] = s_0 * ratio * s_1
    h[3, 2] = s_1 * ratio * s_0
    h[3, 3] = s_1 * ratio * s_1


@inlined
def _add_tangent(s0, force_table, g, h, m, k):  # pragma: no cover - compiled
    """k += w_g Gᵀ h G at Gauss point g, upper triangle, through m = h G (column (j, d) of G is
    A0[g, j] on r_s[d] and B0[g, j] on L r_ss[d])."""
    for a in range(4):
        for j in range(4):
            for d in range(2):
                m[a, 2 * j + d] = s0[g, 0, j] * h[a, d] + s0[g, 1, j] * h[a, 2 + d]
    for r in range(8):
        j, d = r // 2, r % 2
        wa = force_table[2 * g, j]
        wb = force_table[2 * g + 1, j]
        for c in range(r, 8):
            k[r, c] += wa * m[d, c] + wb * m[2 + d, c]


@inlined
def _store_tangent(k, scale, out):  # pragma: no cover - compiled
    """out = the tangent in the original coordinates, both triangles from k's upper one."""
    for r in range(8):
        for c in range(r, 8):
            value = k[r, c] * (scale[r] * scale[c])
            out[r, c] = value
            out[c, r] = value


@inlined
def _store_dlength(k, scale, q, force, fb, L, out):  # pragma: no cover - compiled
    """out = d(force)/dL from L df/dL = (1 - P) f - 2 f_bending - K P q (:func:`.ancf.cable_state`), P = 1
    on the positions; K from k's upper triangle, f_bending from ``fb`` in the scaled coordinates."""
    for r in range(8):
        kpq = 0.0
        for c in range(8):
            if c % 4 < 2:
                upper = k[r, c] if c >= r else k[c, r]
                kpq += upper * (scale[r] * scale[c]) * q[c]
        position = 1.0 if r % 4 < 2 else 0.0
        out[r] = ((1.0 - position) * force[r] - 2.0 * (fb[r] * scale[r]) - kpq) / L
