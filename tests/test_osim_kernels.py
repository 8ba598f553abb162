"""The OpenSim kernels added to the terms (Millard's Bézier curves, the levers of moved tangent
points) answer alike compiled and as their Python code, on the thoracoscapular model's ABD01 excerpt."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from mcdm_pin import jit
from mcdm_pin.model.terms import TermsEvaluator

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def shoulder():
    jit.prepare(policy="wait")
    sys.path.insert(0, str(REPO / "benchmarks"))
    try:
        from shoulder import DEFAULT_MOTION, load
    finally:
        sys.path.pop(0)
    robot, traj = load(DEFAULT_MOTION)
    return robot, traj.subsample(20) if hasattr(traj, "subsample") else traj


def _terms(robot, traj):
    ev = TermsEvaluator(robot)
    out = []
    for k in range(len(traj)):
        t = ev(traj.q[k], traj.qd[k], traj.qdd[k], checked=True)
        out.append(np.concatenate([t.L.ravel(), t.RT.ravel(), t.u.ravel(), t.f_min, t.f_max, t.muscles.gain]))
    return np.array(out), ev


def test_compiled_terms_equal_the_uncompiled_ones(shoulder, monkeypatch):
    robot, traj = shoulder
    fast, ev = _terms(robot, traj)
    assert np.abs(ev._routes.lever).sum() > 0  # the levers are exercised
    with monkeypatch.context() as mp:
        mp.setattr(jit, "_COMPILED", False)
        slow, _ = _terms(robot, traj)
    np.testing.assert_allclose(fast, slow, rtol=1e-12, atol=1e-12 * np.abs(slow).max())


def _bisection(c, x):
    """The curve at ``x`` by bisection on the Bézier parameter of its segment (a reference)."""
    from math import comb

    seg = min(int(np.sum(c.px[:, 5] < x)), len(c.px) - 1)
    basis = lambda u: np.array([comb(5, i) * (1 - u) ** (5 - i) * u ** i for i in range(6)])  # noqa: E731
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if basis(mid) @ c.px[seg] < x else (lo, mid)
    return basis(0.5 * (lo + hi)) @ c.py[seg]


def test_bezier_curves_equal_a_bisection_and_their_lines(shoulder):
    for c in shoulder[0].cables.muscles.muscles[0].curves:  # Millard's f_L, f_V, f_P
        x = np.linspace(c.x0 - 0.3, c.x1 + 0.3, 61)
        y = c(x)
        below, above = x < c.x0, x > c.x1
        np.testing.assert_allclose(y[below], c.y0 + c.dydx0 * (x[below] - c.x0), rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(y[above], c.y1 + c.dydx1 * (x[above] - c.x1), rtol=1e-14, atol=1e-14)
        inside = ~(below | above)
        ref = [_bisection(c, xi) for xi in x[inside]]
        np.testing.assert_allclose(y[inside], ref, rtol=1e-10, atol=1e-12)


def test_millard_range_equals_the_fiber_and_the_curves_in_numpy(shoulder):
    """``bezier_kernels.millard_range`` (the shoulder's 33 Millard muscles in one call) against
    ``OpenSimMuscles.fiber`` (the same compiled pennation model, ``bezier_kernels.pennation``, which
    ``tests/test_osim_paths.py`` checks against OpenSim) and the stacked curves evaluated apart, with
    the range's formulas in numpy, at lengths from slack to clamped and speeds of both signs."""
    from mcdm_pin.model.muscles_osim import _evaluate

    muscles = shoulder[0].cables.muscles
    assert muscles._only_millard
    rng = np.random.default_rng(11)
    m = muscles.size
    for scale in (0.3, 0.8, 1.0, 1.3, 2.0):  # fiber near its minimum (clamped) .. stretched
        ell = muscles.ls + scale * muscles.lo * rng.uniform(0.5, 1.5, m)
        ell_dot = rng.normal(0.0, 0.5, m)
        state = muscles.force_range(ell, ell_dot)
        l, v, cos_a, clamped = muscles.fiber(ell, ell_dot)
        fl, fv, fp = _evaluate(muscles._all, np.concatenate([l, v, l])).reshape(3, -1)
        live = ~clamped
        passive = np.where(live, muscles.f0 * (fp + muscles.damping * v) * cos_a, 0.0)
        gain = np.where(live, muscles.f0 * fl * fv * cos_a, 0.0)
        f_min = np.maximum(passive + gain * muscles.a_min, 0.0)
        f_max = np.maximum(passive + gain * muscles.a_max, 0.0)
        for ours, ref in ((state.passive, passive), (state.gain, gain), (state.f_min, f_min), (state.f_max, f_max)):
            np.testing.assert_allclose(ours, ref, rtol=1e-13, atol=1e-12)
