"""Can a passage take a longer time step? Newmark against every mode integrated exactly over the step
(docs/performance.md, 'Speed': the time step).

Both integrate the exact model's linear catenary (every DOF, the same contact and slack-dropper rules) under
the same pantograph:

- ``newmark``: the exact model as the project runs it (average acceleration, docs/model.md, 'Time
  integration and the fast method'), whose error at Δt = 2 ms ruled out the longer step;
- ``modal``: the catenary in all its modes (K φ = ω² M φ, Rayleigh damping keeps them uncoupled) and the
  pantograph in its state space, each integrated exactly over a step for forces that vary linearly over it
  (a first-order hold: the step's contact and slack-dropper forces, unknown until the step is settled,
  enter through their end-of-step values, as in Newmark). No period error on any mode: what is left at a
  long step is what the hold of the coupling forces loses.

Quick: 5 spans (1 analysed) of the benchmark catenary; full: 10 spans (2 analysed) of the benchmark and the
stitched catenaries (a dense eigensolution of some 4,000 DOFs each: minutes). Rows: σ, mean and extremes of
the filtered contact force, against Newmark's finest step and against Newmark at the project's 1 ms.

    python -m experiments.time_step [--full] [--out results]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg as sla

from catenary_env.analysis.statistics import filtered_contact_force, passage_statistics
from catenary_env.dynamics.active_set import MAX_ACTIVE_SET_ITERATIONS, switch_states
from catenary_env.dynamics.contact_point import start_train
from catenary_env.dynamics.exact import prepare, run
from catenary_env.dynamics.history import start_history, trajectory
from catenary_env.dynamics.linear_system import LinearSystem, linearise
from catenary_env.dynamics.newmark import NewmarkConstants, Trajectory
from catenary_env.dynamics.pantograph import frame_force, pantograph_matrices
from catenary_env.dynamics.protocol import ContactPoint, Passage
from catenary_env.model.design import level_design
from catenary_env.model.presets import load_catenary, load_pantograph
from catenary_env.pipeline import Fidelity, analysis_window, solve_static

from .common import (
    DEFAULT_OUT,
    add_full_option,
    add_out_option,
    markdown_table,
    read_csv,
    run_cli,
    run_study,
    study_dir,
    write_csv,
)
from .model_stamp import stamp_study

NAME = "time-step"
NEWMARK_STEPS = (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4)
"""s; the last is the reference the others are measured against."""
MODAL_STEPS = (4e-3, 2e-3, 1e-3, 5e-4)
"""s."""
PROJECT_STEP = 1e-3
"""s: the step of every fidelity (docs/model.md, 'Mesh and time-step convergence')."""
DIVERGED = 1e7
"""N: a contact force beyond this marks the integration unstable at that step."""


@dataclass(frozen=True)
class Config:
    full: bool = False
    out: Path = DEFAULT_OUT
    speed_kmh: float = 300.0
    # N: fixed, as a convergence study needs (the one of experiments/convergence.py)
    uplift_force: float = 170.4


class Unstable(RuntimeError):
    """The integration diverged."""


def first_order_hold(a: np.ndarray, b: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact discretisation of ẋ = A x + B u, u linear over a step of ``dt`` (s): x₁ = F x₀ + G₀ u₀ + G₁ u₁.

    From the exponential of the augmented system (x, u, u̇) with u̇ constant over the step; batched over the
    leading axes of ``a`` (..., n, n) and ``b`` (..., n, m).
    """
    n, m = a.shape[-1], b.shape[-1]
    z = np.zeros(a.shape[:-2] + (n + 2 * m, n + 2 * m))
    z[..., :n, :n] = a * dt
    z[..., :n, n : n + m] = b * dt
    z[..., n : n + m, n + m :] = np.eye(m) * dt
    e = sla.expm(z)
    ramp = e[..., :n, n + m :] / dt  # the response to u̇ = (u₁ - u₀) / dt, per unit of u₁ - u₀
    return e[..., :n, :n], e[..., :n, n : n + m] - ramp, ramp


@dataclass(frozen=True)
class Modes:
    """Every mode of a linear catenary: ω² (n,), 1/s², and the mass-normalised shapes Φ (n, n)."""

    omega2: np.ndarray
    shapes: np.ndarray

    @classmethod
    def of(cls, system: LinearSystem) -> Modes:
        omega2, shapes = sla.eigh(system.stiffness.toarray(), system.mass.toarray())
        return cls(omega2, shapes)


def modal_passage(system: LinearSystem, modes: Modes, dt: float, passage: Passage) -> Trajectory:
    """The exact model's passage (one pantograph) with every mode and the pantograph integrated exactly over
    steps of ``dt`` (s) under a first-order hold of the forces (module docstring).

    Raises :class:`Unstable` when the contact force diverges.
    """
    started = start_train(system, passage, NewmarkConstants.for_step(dt))[0]
    point, state = started.arrays, started.state
    history = start_history(
        started.time.size, system.support_z.size, system.dropper_force, np.array([started.force0]),
        np.array([state.y[-1]]),
    )  # fmt: skip
    # The catenary: each mode q̈ + (α + β ω²) q̇ + ω² q = φᵀ F.
    w2 = modes.omega2
    a = np.zeros((w2.size, 2, 2))
    a[:, 0, 1], a[:, 1, 0], a[:, 1, 1] = 1.0, -w2, -(system.alpha + system.beta * w2)
    b = np.zeros((w2.size, 2, 1))
    b[:, 1, 0] = 1.0
    F, G0, G1 = first_order_hold(a, b, dt)
    G0, G1 = G0[..., 0], G1[..., 0]
    phi = modes.shapes
    b_phi = np.asarray(system.dropper_elongation @ phi)
    hold_q, hold_v = G1[:, 0], G1[:, 1]  # a mode's end displacement and velocity per unit end force
    k_d, N0, beta = system.dropper_rate, system.dropper_force, system.beta
    # A slack dropper's correction cancels its whole linear force k (Δl + β Δl̇): per unit correction force
    # pair, and per unit contact force (below).
    force_per_pair = k_d[:, None] * ((b_phi * (hold_q + beta * hold_v)) @ b_phi.T)
    # The pantograph: state (y, ẏ), inputs the frame force and the force on the head.
    pm = pantograph_matrices(passage.contact_points[0].pantograph)
    p, head = pm.mass.shape[0], pm.head
    m_inv = np.linalg.inv(pm.mass)
    a_p = np.block([[np.zeros((p, p)), np.eye(p)], [-m_inv @ pm.stiffness, -m_inv @ pm.damping]])
    b_p = np.zeros((2 * p, 2))
    b_p[p:, 0], b_p[p:, 1] = m_inv[:, 0], m_inv[:, head]
    F_p, G0_p, G1_p = first_order_hold(a_p, b_p, dt)
    frame = point.load[0]
    head_compliance = G1_p[head, 1]  # the head's rise per unit upward end force (the contact pushes down)
    kh = system.static.layout.catenary.contact_stiffness
    z_dofs = system.contact_wire.z_dofs
    support_rows = phi[system.support_z]
    # At rest, the initial contact force acting (as the exact model starts).
    q, qd = np.zeros(w2.size), np.zeros(w2.size)
    s = np.concatenate([state.y, state.yd])
    f_prev = started.force0
    g_prev = (point.shape[0] @ phi[z_dofs[point.element[0]]]) * f_prev
    contact, slack = np.array([bool(state.contact[0])]), np.zeros(N0.size, dtype=bool)
    for k in range(1, started.time.size):
        q_known = F[:, 0, 0] * q + F[:, 0, 1] * qd + G0[:, 0] * g_prev
        v_known = F[:, 1, 0] * q + F[:, 1, 1] * qd + G0[:, 1] * g_prev
        s_known = F_p @ s + G0_p @ np.array([frame, -f_prev]) + G1_p[:, 0] * frame
        h_phi = point.shape[k] @ phi[z_dofs[point.element[k]]]
        wire_compliance = h_phi**2 @ hold_q
        g_dz = b_phi @ (h_phi * hold_q)  # dropper elongations per unit contact force (and reciprocally)
        force_per_contact = k_d * (g_dz + beta * (b_phi @ (h_phi * hold_v)))
        base = N0 + k_d * (b_phi @ q_known + beta * (b_phi @ v_known))
        gap_known = np.array([s_known[head] - point.wire_z[k] - h_phi @ q_known])
        contact, slack, f, idx, lam, elastic, resolved = _settle(
            contact, slack, gap_known, wire_compliance + head_compliance, g_dz, base, force_per_contact,
            force_per_pair, kh,
        )  # fmt: skip
        if not abs(f[0]) < DIVERGED:
            raise Unstable(f"contact force {f[0]:.3g} N at step {k}")
        g = h_phi * f[0] + b_phi[idx].T @ lam
        q, qd = q_known + hold_q * g, v_known + hold_v * g
        s = s_known - G1_p[:, 1] * f[0]
        g_prev, f_prev = g, f[0]
        transmitted = np.where(slack, 0.0, elastic)
        np.minimum(history.dropper_min, transmitted, out=history.dropper_min)
        np.maximum(history.dropper_max, transmitted, out=history.dropper_max)
        history.counts[:] += (idx.size > 0, not resolved)
        history.force[0, k], history.head_height[0, k] = f[0], s[head]
        history.wire_uplift[0, k], history.support_uplift[k] = h_phi @ q, support_rows @ q
    return trajectory(history, started.time, (started.position,), system.static.layout.support_x)


def _settle(
    contact: np.ndarray,
    slack: np.ndarray,
    gap_known: np.ndarray,
    compliance: float,
    g_dz: np.ndarray,
    base: np.ndarray,
    force_per_contact: np.ndarray,
    force_per_pair: np.ndarray,
    kh: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, bool]:
    """The step's contact force and slack droppers by the active-set rules of docs/model.md ('One small
    problem per step'), where a dropper's force has its own compliances (its rate part differs from the
    elongation's, so the project's ``settle``, written for Newmark, does not apply as it is). Returns the
    contact and slack states, f (1,), the slack droppers and their forces λ, every dropper's linear force
    and whether the iteration settled."""
    slack = slack.copy()
    for iteration in range(MAX_ACTIVE_SET_ITERATIONS):
        idx = np.flatnonzero(slack)
        m = idx.size
        A, r = np.eye(1 + m), np.zeros(1 + m)
        if contact[0]:
            A[0, 0] += kh * compliance
            A[0, 1:] = kh * g_dz[idx]
            r[0] = kh * gap_known[0]
        A[1:, 0] = -force_per_contact[idx]
        A[1:, 1:] -= force_per_pair[np.ix_(idx, idx)]
        r[1:] = base[idx]
        sol = np.linalg.solve(A, r)
        f, lam = sol[:1], sol[1:]
        gap = gap_known - compliance * f - g_dz[idx] @ lam
        elastic = base + force_per_contact * f[0] + force_per_pair[:, idx] @ lam
        new_contact, new_slack = gap > 0.0, elastic < 0.0
        if np.array_equal(new_contact, contact) and np.array_equal(new_slack, slack):
            return contact, slack, f, idx, lam, elastic, True
        contact, slack = switch_states(contact, slack, new_contact, new_slack, kh * gap, elastic, iteration)
    return contact, slack, f, idx, lam, elastic, False


def main(config: Config) -> Path:
    n_spans, analysis = (10, 2) if config.full else (5, 1)
    presets = ("benchmark", "stitched") if config.full else ("benchmark",)
    rows = []
    for preset in presets:
        catenary = load_catenary(preset)
        pantograph = load_pantograph(catenary.pantograph)
        fidelity = Fidelity(n_spans=n_spans, analysis_spans=analysis, dynamics="exact")
        system = linearise(solve_static(catenary, level_design(catenary), fidelity))
        window = analysis_window(catenary, fidelity)
        passage = Passage(
            config.speed_kmh / 3.6,
            (ContactPoint(pantograph, frame_force(system, pantograph, config.uplift_force)),),
        )
        start = time.perf_counter()
        modes = Modes.of(system)
        print(f"{preset}: {system.n_dofs} modes in {time.perf_counter() - start:.0f} s", flush=True)
        runs = [("newmark", dt) for dt in NEWMARK_STEPS] + [("modal", dt) for dt in MODAL_STEPS]
        for integrator, dt in runs:
            start = time.perf_counter()
            try:
                if integrator == "newmark":
                    tr = run(prepare(system, Fidelity(time_step=dt, dynamics="exact")), passage)
                else:
                    tr = modal_passage(system, modes, dt, passage)
            except Unstable as err:
                print(f"  {integrator} {dt * 1e3:g} ms: unstable ({err})", flush=True)
                rows.append(_row(preset, integrator, dt, stable=0))
                continue
            st = passage_statistics(tr, window, filtered_contact_force(tr))
            rows.append(
                _row(
                    preset, integrator, dt, stable=1, n_dofs=system.n_dofs, sigma_N=st.std, mean_N=st.mean,
                    actual_max_N=st.actual_max, actual_min_N=st.actual_min, slack_steps=tr.slack_steps,
                    wall_time_s=time.perf_counter() - start,
                )
            )  # fmt: skip
            print(f"  {integrator} {dt * 1e3:g} ms: σ = {st.std:.3f} N", flush=True)
    _compare(rows)
    folder = study_dir(config.out, NAME)
    write_csv(folder / "time_step.csv", rows)
    stamp_study(folder, presets)
    report(folder)
    return folder


_COLUMNS = (
    "catenary", "integrator", "time_step_s", "stable", "n_dofs", "sigma_N", "mean_N", "actual_max_N",
    "actual_min_N", "slack_steps", "wall_time_s", "sigma_vs_finest_percent",
    "extremes_vs_finest_percent_of_mean", "sigma_vs_1ms_percent", "extremes_vs_1ms_percent_of_mean",
)  # fmt: skip


def _row(catenary: str, integrator: str, time_step: float, **values: float) -> dict:
    """A row of ``time_step.csv``: every column, NaN where ``values`` give none (an unstable run's figures,
    and the comparisons until :func:`_compare`)."""
    given = {"catenary": catenary, "integrator": integrator, "time_step_s": time_step, **values}
    return dict.fromkeys(_COLUMNS, np.nan) | given


def _compare(rows: list[dict]) -> None:
    """Each row against Newmark's finest step and against Newmark at the project's step, same catenary: σ in
    % of σ, the extremes in % of the mean (the accuracy contract's measures, docs/performance.md)."""
    for row in rows:
        if not row["stable"]:
            continue
        for name, dt in (("finest", NEWMARK_STEPS[-1]), ("1ms", PROJECT_STEP)):
            ref = next(
                r
                for r in rows
                if (r["catenary"], r["integrator"], r["time_step_s"]) == (row["catenary"], "newmark", dt)
            )
            row[f"sigma_vs_{name}_percent"] = 100.0 * (row["sigma_N"] / ref["sigma_N"] - 1.0)
            row[f"extremes_vs_{name}_percent_of_mean"] = (
                100.0
                * max(
                    abs(row["actual_max_N"] - ref["actual_max_N"]),
                    abs(row["actual_min_N"] - ref["actual_min_N"]),
                )
                / ref["mean_N"]
            )


def report(folder: Path) -> str:
    """Markdown table from the CSV (no simulation)."""
    rows = read_csv(folder / "time_step.csv")
    table = markdown_table(
        [r for r in rows if r["stable"]],
        [
            ("catenary", "catenary", "s"),
            ("integrator", "integration", "s"),
            ("time_step_s", "Δt (s)", "g"),
            ("sigma_N", "σ (N)", ".3f"),
            ("sigma_vs_finest_percent", "σ vs finest (%)", "+.2f"),
            ("sigma_vs_1ms_percent", "σ vs 1 ms (%)", "+.2f"),
            ("extremes_vs_finest_percent_of_mean", "extremes vs finest (% of mean)", ".2f"),
            ("extremes_vs_1ms_percent_of_mean", "extremes vs 1 ms (% of mean)", ".2f"),
            ("wall_time_s", "time (s)", ".1f"),
        ],
    )
    notes = "".join(
        f"\n{r['catenary']}, {r['integrator']} at {r['time_step_s']:g} s: unstable."
        for r in rows
        if not r["stable"]
    )
    (folder / "time_step.md").write_text(table + "\n" + notes + "\n", encoding="utf-8")
    return table


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``catenary experiment time-step`` and ``python -m experiments.time_step``)."""
    add_full_option(parser, "10 spans (2 analysed) of both catenaries (minutes), instead of 5 spans of one")
    add_out_option(parser)


def cli(argv: list[str] | None = None) -> int:
    """``python -m experiments.time_step``: the study with the options of :func:`add_arguments`."""
    return run_study(sys.modules[__name__], argv, "python -m experiments.time_step")


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "python -m experiments.time_step"))
