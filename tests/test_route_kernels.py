"""The compiled route pass (``route_kernels.route_pass``) against the same function uncompiled (its
Python code, as ``jit.kernels`` hands it out before ``mcdm-pin compile``: ``wrapping.py``'s maths run
as Python), on MyoSuite's arm (97 wraps over spheres and cylinders, with side points outside and
inside) at 50 states, alone and through the whole terms; and against the public wrap functions
(``wrap_sphere``, ``wrap_cylinder``) one wrap at a time."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mcdm_pin import Robot, jit
from mcdm_pin.model import route_kernels
from mcdm_pin.model.routes import RoutePaths
from mcdm_pin.model.terms import TermsEvaluator
from mcdm_pin.model.wrapping import wrap_cylinder, wrap_sphere

ROOT = Path(__file__).resolve().parents[1]
STATES = 50


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    import os

    here = os.getcwd()
    os.chdir(tmp_path_factory.mktemp("mujoco"))  # MuJoCo writes MUJOCO_LOG.TXT where it runs
    try:
        robot = Robot.load(ROOT / "robots" / "myosuite" / "myoarm.yaml")
    finally:
        os.chdir(here)
    rng = np.random.default_rng(11)
    lo, hi = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    lo, hi = np.where(np.isfinite(lo), lo, -1.0), np.where(np.isfinite(hi), hi, 1.0)
    states = []
    for _ in range(STATES):
        q, v, a = robot.couplings.fill(rng.uniform(lo, hi), rng.normal(size=robot.nv), rng.normal(size=robot.nv))
        states.append((q, v, a))
    return robot, states


def _placements(ev, q):
    import pinocchio as pin

    pin.forwardKinematics(ev.model, ev.data, q)
    return np.array([ev.data.oMi[j].homogeneous for j in ev._keys])


def test_compiled_route_pass_equals_the_uncompiled_one(arm):
    robot, states = arm
    ev = TermsEvaluator(robot)
    key = np.full(robot.model.njoints, -1)
    key[ev._keys] = np.arange(len(ev._keys))
    fast, slow = RoutePaths(robot.cables, key), RoutePaths(robot.cables, key)
    fast._pass = route_kernels.route_pass  # the dispatcher (compiles on its first call when not cached)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(jit, "_COMPILED", False)
        slow._pass = jit.kernels("model.route_kernels").route_pass
    assert not hasattr(slow._pass, "overloads")  # plain Python
    engaged = np.zeros(len(robot.cables.wraps), dtype=int)
    for q, _, _ in states:
        oM = _placements(ev, q)
        (ra, la), (rb, lb) = fast(oM), slow(oM)
        for x, y in zip((*ra, la), (*rb, lb)):
            scale = max(1.0, float(np.abs(y).max(initial=0.0)))
            assert np.abs(np.asarray(x, dtype=float) - np.asarray(y, dtype=float)).max(initial=0.0) <= 1e-14 * scale
        assert np.array_equal(fast.engaged, slow.engaged)
        engaged += fast.engaged
    assert engaged.sum() > 0.2 * STATES * len(engaged), "a good share of the arm's wraps engage"


def test_compiled_terms_equal_the_uncompiled_ones(arm):
    robot, states = arm
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(jit, "_COMPILED", True)  # the dispatchers (each compiles on its first call when not cached)
        fast = TermsEvaluator(robot)
        mp.setattr(jit, "_COMPILED", False)
        slow = TermsEvaluator(robot)
    assert hasattr(fast._routes._pass, "overloads") and not hasattr(slow._routes._pass, "overloads")
    for q, v, a in states:
        s, f = slow(q, v, a), fast(q, v, a)
        for name in ("lengths", "L_full", "RT", "points", "f_min", "f_max"):
            x, y = getattr(f, name), getattr(s, name)
            assert np.abs(x - y).max() <= 1e-14 * max(1.0, np.abs(y).max()), name


def test_route_pass_tangent_points_equal_the_public_wrap_functions(arm):
    """Each engaged wrap's tangent points and arc (through the cable's length) from the route pass
    equal ``wrap_sphere``/``wrap_cylinder`` on the same end points in the surface's frame."""
    robot, states = arm
    ev = TermsEvaluator(robot)
    cables = robot.cables
    for q, _, _ in states[:10]:
        oM = _placements(ev, q)
        routes = ev._routes
        routes(oM)
        oR, op = oM[:, :3, :3], oM[:, :3, 3]
        for w, wr in enumerate(cables.wraps):
            kg = routes.point_key[routes.n_points + 2 * w]
            Rg = oR[kg] @ wr.placement.rotation
            pg = oR[kg] @ wr.placement.translation + op[kg]

            def local(k_point):
                k = routes.point_key[k_point]
                return Rg.T @ (oR[k] @ cables.point_local[k_point] + op[k] - pg)

            side = None
            if wr.side_joint >= 0:
                ks = ev._keys.index(wr.side_joint)
                side = Rg.T @ (oR[ks] @ wr.side_local + op[ks] - pg)
            ref = (wrap_cylinder if wr.kind == "cylinder" else wrap_sphere)(local(wr.a), local(wr.b), wr.radius, side)
            assert ref.engaged == routes.engaged[w]
            if ref.engaged:
                slot = routes.n_points + 2 * w
                for t_ref, t in ((ref.t0, routes.point_local[slot]), (ref.t1, routes.point_local[slot + 1])):
                    mine = wr.placement.rotation.T @ (t - wr.placement.translation)
                    assert np.abs(mine - t_ref).max() < 1e-14


def test_the_route_pass_is_registered_and_its_sources_stamp_the_cache():
    """``mcdm-pin compile`` compiles the route pass with the other kernels, and a change to the wrap
    maths (``wrapping.py``, compiled inline into it) or to the pass itself invalidates the cache."""
    assert "mcdm_pin.model.route_kernels.route_pass" in jit.entry_points()
    assert {"wrapping.py", "route_kernels.py"} <= {p.name for p in jit.kernel_sources()}
