"""The active set of contact and slack droppers (catenary_env/dynamics/active_set.py): the compiled loops'
settle_in_place against settle, and its stop and resume for a caller that fills G's rows as droppers go
slack (docs/performance.md, 'A slack dropper's responses when it first goes slack')."""

from __future__ import annotations

import numpy as np
import pytest

from catenary_env.dynamics.active_set import Droppers, settle, settle_in_place, settle_workspace


def _problem(seed: int, n_drop: int = 12):
    """One contact point and ``n_drop`` droppers whose elongations leave several of them slack, coupled
    through a symmetric positive definite G (m/N), so that the active set takes several iterations."""
    rng = np.random.default_rng(seed)
    root = rng.normal(size=(n_drop, n_drop)) * 1e-4
    G = root @ root.T + np.eye(n_drop) * 1e-7
    droppers = Droppers.for_step(np.full(n_drop, 1e5), rng.uniform(50.0, 150.0, n_drop), 1e-4, 2e3)
    dl_known = -droppers.force / droppers.kappa * rng.uniform(0.5, 1.5, n_drop)
    g_dc = rng.uniform(0.0, 2e-6, (1, n_drop))
    return dict(
        contact=np.array([True]),
        slack=np.zeros(n_drop, dtype=bool),
        gap_known=np.array([1e-3]),
        c_cc=np.array([[2e-5]]),
        g_dc=g_dc,
        dl_known=dl_known,
        rate_term=np.zeros(n_drop),
        kh=5e4,
        droppers=droppers,
        G=G,
    )


def _in_place(p, G, ready, fill=None):  # noqa: ANN001, ANN202
    """settle_in_place over ``p`` with ``G``'s rows marked by ``ready``; ``fill(slack)`` fills the rows of
    the slack droppers whenever it stops for them. Returns (contact, slack, f, λ, slack indices, resolved,
    the number of stops)."""
    contact, slack = p["contact"].copy(), p["slack"].copy()
    work = settle_workspace(1, slack.size)
    args = (p["gap_known"], p["c_cc"], p["g_dc"], p["dl_known"], p["rate_term"], p["kh"], p["droppers"])
    iteration, stops = 0, 0
    while iteration >= 0:
        m, resolved, iteration = settle_in_place(contact, slack, *args, G, work, ready, iteration)
        if iteration >= 0:
            stops += 1
            fill(slack)
    return contact, slack, work[6].copy(), work[2][:m].copy(), work[3][:m].copy(), resolved, stops


@pytest.mark.parametrize("seed", range(6))
def test_settle_in_place_is_settle(seed):
    p = _problem(seed)
    ready = np.ones(p["slack"].size, dtype=bool)
    contact, slack, f, lam, idx, resolved, stops = _in_place(p, p["G"], ready)
    expected = settle(
        p["contact"], p["slack"], p["gap_known"], p["c_cc"], p["g_dc"], p["dl_known"], p["rate_term"],
        p["kh"], p["droppers"], p["G"],
    )  # fmt: skip
    assert stops == 0 and resolved and expected.resolved
    assert np.array_equal(slack, expected.slack) and np.array_equal(contact, expected.contact)
    assert slack.sum() >= 2  # the case exercises slack droppers
    assert np.array_equal(idx, expected.slack_droppers)
    np.testing.assert_allclose(f, expected.force, rtol=1e-12)
    np.testing.assert_allclose(lam, expected.slack_forces, rtol=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_stopping_for_rows_and_resuming_changes_nothing(seed):
    """With no row of G ready at first (the others NaN, so that a row read before it is filled would show),
    settle_in_place stops as droppers go slack and, once their rows are filled, ends where it ends with G
    whole, to the last bit."""
    p = _problem(seed)
    whole = _in_place(p, p["G"], np.ones(p["slack"].size, dtype=bool))
    G = np.full_like(p["G"], np.nan)
    ready = np.zeros(p["slack"].size, dtype=bool)

    def fill(slack: np.ndarray) -> None:
        for q in np.flatnonzero(slack & ~ready):
            G[q] = p["G"][q]
            ready[q] = True

    parts = _in_place(p, G, ready, fill)
    assert parts[-1] >= 1  # it stopped
    for a, b in zip(whole[:-1], parts[:-1], strict=True):
        assert np.array_equal(a, b)
    assert np.all(ready[parts[1]])  # every slack dropper's row was filled
