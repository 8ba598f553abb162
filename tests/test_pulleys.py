"""Rotating and screw pulleys (``mcdm_pin.model.pulleys``, computed in the route pass), against CASPR's
own formulas written out independently in ``tests/caspr_newton.py`` (``base_pulley_exit``,
``screw_pulley_exit``: CASPR's ``ComputePulleyLeavingLocation`` of each class, MATLAB's ``roots`` and
CASPR's root selection), central finite differences, CASPR's Newton-Euler, and Clarabel; and the
compiled route pass against the uncompiled one."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin import Robot, jit
from mcdm_pin.exceptions import ModelError, SidecarError, StateError
from mcdm_pin.model import route_kernels
from mcdm_pin.model.cables import Cable, CableSet, Pulley, RotatingPulley, ScrewDrive
from mcdm_pin.model.routes import RoutePaths
from mcdm_pin.model.terms import TermsEvaluator, cable_terms

from . import caspr_newton as cn
from .caspr_library_check import (OBJ_TOL, REPO, X_TOL, clarabel_alone, compare, objective_agreement,
                                  ours_from_caspr, reference_state, solve_case1, worst)

CASPR = REPO / "tests" / "data" / "caspr"  # CASPR's XML of the pulley models (committed)
RADIUS = 0.045
# (entry point, entry direction) of four base pulleys round a box, one of them not axis-aligned
BASE = [((0.08, 2.2, 1.9), (0.0, 0.0, 1.0)), ((2.2, 2.2, 0.1), (0.0, 0.0, -1.0)),
        ((2.2, 0.08, 1.9), (0.3, -0.2, 1.0)), ((0.08, 0.08, 0.1), (0.0, 0.0, -1.0))]
SCREW = dict(winch=(2.2, 2.2, 1.9), entry=(0.0, 0.0, 1.0), direction=(0.0, 1.0, 0.0), radius=0.025,
             winch_radius=0.06, groove=0.002, reference=1.7)
CORNERS = [(-0.2, 0.16, 0.07), (0.2, 0.16, -0.07), (0.2, -0.16, 0.07), (-0.2, -0.16, -0.07)]


def _platform():
    """A free-flying platform, and a link on a hinge of the platform that carries a pulley."""
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "platform")
    model.appendBodyToJoint(j, pin.Inertia.FromBox(5.0, 0.4, 0.3, 0.2), pin.SE3.Identity())
    model.addBodyFrame("platform", j, pin.SE3.Identity(), 0)
    h = model.addJoint(j, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.1])), "hinge")
    model.appendBodyToJoint(h, pin.Inertia.FromBox(1.0, 0.3, 0.05, 0.05), pin.SE3.Identity())
    model.addBodyFrame("arm", h, pin.SE3.Identity(), 0)
    return model


def _lead():
    return SCREW["groove"] / (np.pi * 2 * SCREW["winch_radius"])


def _cables(model):
    cables = [Cable(f"c{i}", (RotatingPulley("universe", F, u, RADIUS), ("platform", CORNERS[i])), 1.0, 500.0)
              for i, (F, u) in enumerate(BASE[:3])]
    # the last element of a route, on a pulley's branch (divisor 2)
    cables.append(Cable("last", (("universe", (1.1, 1.1, 0.0)), ("platform", (0.0, 0.0, -0.1)), Pulley(2.0),
                                 ("platform", CORNERS[3]),
                                 RotatingPulley("universe", *BASE[3], RADIUS)), 1.0, 500.0))
    # a pulley on a moving link, its cable to a base point
    cables.append(Cable("moving", (RotatingPulley("arm", (0.25, 0.0, 0.0), (1.0, 0.0, 0.0), 0.03),
                                   ("universe", (1.5, 2.0, 0.3))), 1.0, 500.0))
    screw = ScrewDrive(SCREW["direction"], _lead(), SCREW["reference"], cn.SCREW_OUTLET)
    cables.append(Cable("screw", (RotatingPulley("universe", SCREW["winch"], SCREW["entry"], SCREW["radius"], screw),
                                  ("platform", (0.2, 0.16, 0.07))), 1.0, 500.0))
    return CableSet(model, cables)


def _states(model, n, seed=3):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        q = pin.neutral(model)
        q[:3] = rng.uniform([0.7, 0.7, 0.6], [1.5, 1.5, 1.4])
        q[3:7] = pin.Quaternion(pin.exp3(rng.uniform(-0.4, 0.4, 3))).coeffs()
        q[7] = rng.uniform(-1.0, 1.0)
        out.append(q)
    return out


@pytest.fixture(scope="module")
def platform():
    model = _platform()
    return model, model.createData(), _cables(model)


def _reference_lengths(model, data, q):
    """Each cable's length by CASPR's formulas (exit point, arc ``R acos``), screw by CASPR's rule."""
    pin.framesForwardKinematics(model, data, q)

    def at(frame, p):
        return data.oMf[model.getFrameId(frame)].act(np.array(p, dtype=float))

    out = []
    for i, (F, u) in enumerate(BASE[:3]):
        B = at("platform", CORNERS[i])
        A, arc = cn.base_pulley_exit(np.array(F), np.array(u), B, RADIUS)
        out.append(arc + np.linalg.norm(B - A))
    B = at("platform", CORNERS[3])
    A, arc = cn.base_pulley_exit(np.array(BASE[3][0]), np.array(BASE[3][1]), B, RADIUS)
    out.append(np.linalg.norm(at("platform", (0.0, 0.0, -0.1)) - (1.1, 1.1, 0.0)) + (arc + np.linalg.norm(B - A)) / 2.0)
    M = data.oMf[model.getFrameId("arm")]  # the moving pulley, in its body's frame
    B = M.actInv(np.array([1.5, 2.0, 0.3]))
    A, arc = cn.base_pulley_exit(np.array([0.25, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), B, 0.03)
    out.append(arc + np.linalg.norm(B - A))
    p = dict(winch_groove_width=SCREW["groove"], winch_radius=SCREW["winch_radius"],
             constant_winch_point=np.array(SCREW["winch"]), winch_vector=np.array(SCREW["direction"]),
             l0_offset=SCREW["reference"], cable_pulley_entry_vector=np.array(SCREW["entry"]),
             pulley_radius=SCREW["radius"])
    B = at("platform", (0.2, 0.16, 0.07))
    D, arc = cn.screw_pulley_exit(p, B)
    out.append(arc + np.linalg.norm(B - D))
    return np.array(out)


def test_lengths_equal_caspr_formulas(platform):
    """Exit point and arc of CASPR's two pulley classes (their arcs by ``acos``: the wrap angles stay
    below pi here), the pulley as a route's first or last element, on a pulley's branch, on a moving
    link, and on a screw-driven outlet."""
    model, data, cables = platform
    for q in _states(model, 20):
        ours = cable_terms(model, data, cables, q).lengths
        ref = _reference_lengths(model, data, q)
        assert np.abs(ours - ref).max() <= 1e-13 * np.abs(ref).max()


def test_exit_points_equal_caspr(platform):
    """The route point slot of a base pulley holds CASPR's exit point ``r_A``."""
    model, data, cables = platform
    q = _states(model, 1)[0]
    t = cable_terms(model, data, cables, q)
    pin.framesForwardKinematics(model, data, q)
    B = data.oMf[model.getFrameId("platform")].act(np.array(CORNERS[0]))
    A, _ = cn.base_pulley_exit(np.array(BASE[0][0]), np.array(BASE[0][1]), B, RADIUS)
    rp = cables.rotating[0]
    assert np.abs(t.points[rp.point] - A).max() < 1e-14


def _fd(model, data, cables, q, eps=1e-6):
    L = np.zeros((cables.m, model.nv))
    for i in range(model.nv):
        e = np.zeros(model.nv)
        e[i] = eps
        lp = cable_terms(model, data, cables, pin.integrate(model, q, e)).lengths
        lm = cable_terms(model, data, cables, pin.integrate(model, q, -e)).lengths
        L[:, i] = (lp - lm) / (2 * eps)
    return L


def test_L_is_the_derivative_of_the_length(platform):
    """Rotating pulleys: ``L`` equals central differences of the lengths to 1e-7 relative (the exit
    point, fixed on the pulley's body at the instant, gives the exact derivative). A screw outlet:
    ``L`` is the derivative at a fixed outlet (a rotating pulley whose entry stands where the screw
    puts it), and the outlet's own motion adds a term of the order of the lead."""
    model, data, cables = platform
    rotating = [k for k in range(cables.m) if cables.names[k] != "screw"]
    s = cables.names.index("screw")
    for q in _states(model, 5):
        t = cable_terms(model, data, cables, q)
        fd = _fd(model, data, cables, q)
        scale = np.abs(t.L[rotating]).max()
        assert np.abs(t.L[rotating] - fd[rotating]).max() <= 1e-7 * scale
        F = _screw_entry(model, data, q)
        frozen = CableSet(model, [Cable("f", (RotatingPulley("universe", F, SCREW["entry"], SCREW["radius"]),
                                              ("platform", (0.2, 0.16, 0.07))), 1.0, 500.0)])
        fd_frozen = _fd(model, data, frozen, q)
        assert np.abs(t.L[s] - fd_frozen[0]).max() <= 1e-7 * np.abs(t.L[s]).max()
        assert 0 < np.abs(t.L[s] - fd[s]).max() <= 2 * _lead() * np.abs(t.L[s]).max()


def _screw_entry(model, data, q):
    """CASPR's screw outlet: the larger root of its quadratic (MATLAB's roots), then the entry point."""
    pin.framesForwardKinematics(model, data, q)
    B = data.oMf[model.getFrameId("platform")].act(np.array([0.2, 0.16, 0.07]))
    W, v, k, l0 = np.array(SCREW["winch"]), np.array(SCREW["direction"]), _lead(), SCREW["reference"]
    c = B - W
    delta = max(np.real(np.roots([1 - k ** 2 * v @ v, 2 * l0 + 2 * k * c @ v, l0 ** 2 - c @ c])))
    return W + (cn.SCREW_OUTLET + k * delta) * v


def test_wrap_beyond_half_a_turn_stays_the_derivative():
    """The cable's other end behind the swivel axis: the wrap passes pi (CASPR's ``acos`` folds it back,
    so its length is no longer the path's); ours is the path's, and ``L`` its derivative."""
    model = _platform()
    data = model.createData()
    cables = CableSet(model, [Cable("c", (RotatingPulley("universe", (1.0, 1.0, 2.0), (0.0, 0.0, 1.0), 0.3),
                                          ("platform", (0.0, 0.0, 0.0))), 1.0, 500.0)])
    q = pin.neutral(model)
    q[:3] = [0.9, 1.0, 1.0]  # below the pulley, 0.1 m across the axis: behind the centre (0.3 m across)
    t = cable_terms(model, data, cables, q)
    B = q[:3]
    A, arc_caspr = cn.base_pulley_exit(np.array([1.0, 1.0, 2.0]), np.array([0.0, 0.0, 1.0]), B, 0.3)
    theta = (t.lengths[0] - np.linalg.norm(B - A)) / 0.3
    assert np.pi < theta < 2 * np.pi and abs(0.3 * (2 * np.pi - theta) - arc_caspr) < 1e-12
    fd = _fd(model, data, cables, q)
    assert np.abs(t.L - fd).max() <= 1e-7 * np.abs(t.L).max()


def test_no_exit_point_is_a_state_error(platform):
    model, data, _ = platform
    cables = CableSet(model, [Cable("c", (RotatingPulley("universe", (1.0, 1.0, 2.0), (0.0, 0.0, 1.0), 0.05),
                                          ("platform", (0.0, 0.0, 0.0))), 1.0, 500.0)])
    q = pin.neutral(model)
    q[:3] = [1.0, 1.0, 1.0]  # on the swivel axis
    with pytest.raises(StateError, match="cable 'c': rotating pulley: .*swivel axis"):
        cable_terms(model, data, cables, q)
    q[:3] = [1.05, 1.0, 2.0]  # the pulley's centre
    with pytest.raises(StateError, match="inside the pulley's circle"):
        cable_terms(model, data, cables, q)


def test_a_rotating_pulley_stands_at_an_end_next_to_a_point():
    model = _platform()
    rp = RotatingPulley("universe", (1.0, 1.0, 2.0), (0.0, 0.0, 1.0), 0.05)
    for route in [(("universe", (0, 0, 0)), rp, ("platform", (0, 0, 0))), (rp, Pulley(2.0), ("platform", (0, 0, 0)))]:
        with pytest.raises(ModelError, match="first or the last element"):
            CableSet(model, [Cable("c", route, 1.0, 10.0)])
    with pytest.raises(ModelError, match="radius > 0"):
        CableSet(model, [Cable("c", (RotatingPulley("universe", (1, 1, 2), (0, 0, 1), 0.0), ("platform", (0, 0, 0))),
                               1.0, 10.0)])
    bad = RotatingPulley("universe", (1, 1, 2), (0, 0, 1), 0.05, ScrewDrive((0, 1, 0), 2.0, 1.0, 0.0))
    with pytest.raises(ModelError, match="lead"):
        CableSet(model, [Cable("c", (bad, ("platform", (0, 0, 0))), 1.0, 10.0)])


def test_sidecar_rotating_pulley(tmp_path):
    """docs/sidecar.md's ``rotating_pulley`` element, and its checks."""
    import shutil

    import yaml

    src = REPO / "robots" / "caspr" / "SpiderBot_UR3_Test" / "SpiderBot_UR3_Test.yaml"
    shutil.copy(REPO / "urdf" / "caspr" / "SpiderBot_UR3_Test.urdf", tmp_path / "r.urdf")
    data = yaml.safe_load(src.read_text())
    data["urdf"] = "r.urdf"
    first = data["cables"][0]["route"][0]
    assert set(first) == {"rotating_pulley", "link", "entry", "axis", "screw"}
    (tmp_path / "ok.yaml").write_text(yaml.safe_dump(data))
    robot = Robot.load(tmp_path / "ok.yaml")
    assert len(robot.cables.rotating) == 8 and robot.cables.rotating[0].screw is not None
    first["screw"]["lead"] = 20.0
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(SidecarError, match=r"cables\[0\]\.route\[0\]\.screw\.lead"):
        Robot.load(tmp_path / "bad.yaml")
    first["screw"]["lead"], first["axis"] = 0.005, [0, 0, 0]
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(SidecarError, match=r"cables\[0\]\.route\[0\]\.axis: expected a nonzero vector"):
        Robot.load(tmp_path / "bad.yaml")
    first["axis"] = [0, 0, 1]
    route = data["cables"][0]["route"]
    data["cables"][0]["route"] = [route[1], route[0], {"link": "base", "point": [0, 0, 0]}]
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(SidecarError, match=r"cables\[0\]\.route: cable 'X': route\[1\]: a rotating pulley must "
                                           r"be the first or the last element"):
        Robot.load(tmp_path / "bad.yaml")


def _model_files(name):
    return CASPR / name / f"{name}_bodies.xml", CASPR / name / f"{name}_cables.xml"


@pytest.mark.parametrize("name", ["SpiderBot_UR3", "SpiderBot_UR3_Test"])
def test_committed_models_match_their_reference(name):
    """The committed conversions (default cable sets: rotating pulleys, screw pulleys) against the
    reference values ``tools/caspr_library.py reference`` computed with ``caspr_newton`` (CASPR's
    pulley formulas included), to 1e-9 relative, on a plain clone."""
    from mcdm_pin import load_trajectory

    from .caspr_library_check import load_library, load_reference, reference_states, state_of

    entry = next(m for m in load_library()["models"] if m["model"] == name)
    assert entry["status"] == "imported" and entry["cable_set"] == "CUcablerobot"
    robot = Robot.load(REPO / entry["sidecar"])
    assert len(robot.cables.rotating) == 8
    traj = load_trajectory(robot, entry["table_trajectory"]) if entry["table_trajectory"] else None
    states = reference_states(load_reference(), name)
    errors = [compare(robot, entry["links"], st, *state_of(robot, entry, st, traj)) for st in states]
    w = worst(errors)
    assert len(states) >= 2 and all(val <= 1e-9 for val in w.values()), w


def test_terms_equal_caspr_newton_euler(tmp_path):
    """Lengths, ``L``, ``M``, ``tau`` and the interaction wrench maps of both SpiderBot_UR3 models as
    committed, and of CAROCA's ``with_rotating_pulleys`` set imported here, against CASPR's Newton-Euler
    with CASPR's pulley formulas, computed here from CASPR's XML at states away from ``q_initial``, to
    1e-9 relative."""
    from mcdm_pin.caspr import import_caspr

    links = ["UR3_base", "UR3_shoulder", "UR3_upper_arm", "UR3_forearm", "UR3_wrist_1", "UR3_wrist_2", "UR3_wrist_3"]
    for name, n_states, cable_set in (("SpiderBot_UR3", 1, None), ("SpiderBot_UR3_Test", 3, None),
                                      ("CAROCA", 2, "with_rotating_pulleys")):
        bodies, cables = _model_files(name)
        model = cn.Model.from_xml(bodies, cables, cable_set)
        if cable_set is None:
            robot = Robot.load(REPO / "robots" / "caspr" / name / f"{name}.yaml")
        else:
            res = import_caspr(bodies, cables, tmp_path / name, cable_set=cable_set)
            robot = Robot.load(res.sidecar)
            links = [link.ident for link in res.bodies.links]
            assert len(robot.cables.rotating) == robot.m
        rng = np.random.default_rng(5)
        q0 = np.concatenate([link.q_initial for link in model.links])
        errors = []
        for _ in range(n_states):
            q, qd, qdd = q0 + rng.uniform(-0.3, 0.3, model.n), rng.uniform(-1, 1, model.n), rng.uniform(-1, 1, model.n)
            x, v, a = ours_from_caspr(bodies, robot, q, qd, qdd)
            errors.append(compare(robot, links[:len(model.links)], reference_state(model, q, qd, qdd),
                                  robot.configuration(x), v, a))
        w = worst(errors)
        assert all(val <= 1e-9 for val in w.values()), (name, w)


def _trajectories():
    """SpiderBot_UR3's ``line_test``, and for SpiderBot_UR3_Test (CASPR gives it no trajectory) the
    same motion of its one body, the UR3's base."""
    from mcdm_pin import load_trajectory
    from mcdm_pin.trajectory import Trajectory

    ur3 = Robot.load(REPO / "robots" / "caspr" / "SpiderBot_UR3" / "SpiderBot_UR3.yaml")
    tr = load_trajectory(ur3, "line_test").subsample(9)
    test = Robot.load(REPO / "robots" / "caspr" / "SpiderBot_UR3_Test" / "SpiderBot_UR3_Test.yaml")
    return [(ur3, tr), (test, Trajectory("base of line_test", tr.t, tr.q[:, :7], tr.qd[:, :6], tr.qdd[:, :6]))]


@pytest.mark.parametrize("k", [0, 1], ids=["SpiderBot_UR3", "SpiderBot_UR3_Test"])
def test_case1_agrees_with_clarabel(k):
    """Case 1 along the trajectory: the default chain and Clarabel give the same status at every
    instant and objectives to 1e-6 relative where optimal; Clarabel alone, forces to X_TOL."""
    robot, tr = _trajectories()[k]
    prox, clar = solve_case1(robot, tr)
    assert list(prox.status) == list(clar.status)
    n, diff = objective_agreement(prox, clar)
    assert n >= 3 and diff <= OBJ_TOL, (n, diff)
    alone = clarabel_alone(robot, tr)
    assert not alone["mismatch"] and alone["objective"] <= OBJ_TOL and alone["x"] <= X_TOL, alone


def test_compiled_route_pass_equals_the_uncompiled_one(platform):
    """The compiled route pass and its Python code give the same exit points, arcs and terms."""
    model, data, cables = platform
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(jit, "_COMPILED", True)
        fast = TermsEvaluator(model, cables)
        mp.setattr(jit, "_COMPILED", False)
        slow = TermsEvaluator(model, cables)
    assert hasattr(fast._routes._pass, "overloads") and not hasattr(slow._routes._pass, "overloads")
    key = np.full(model.njoints, -1)
    key[fast._keys] = np.arange(len(fast._keys))
    a_paths, b_paths = RoutePaths(cables, key), RoutePaths(cables, key)
    a_paths._pass = route_kernels.route_pass
    for q in _states(model, 10, seed=9):
        f, s = fast(q), slow(q)
        for name in ("lengths", "L_full", "RT", "points"):
            x, y = getattr(f, name), getattr(s, name)
            assert np.abs(x - y).max() <= 1e-14 * max(1.0, np.abs(y).max()), name
        pin.forwardKinematics(model, fast.data, q)
        oM = np.array([fast.data.oMi[j].homogeneous for j in fast._keys])
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(jit, "_COMPILED", False)
            b_paths._pass = jit.kernels("model.route_kernels").route_pass
        (ra, la), (rb, lb) = a_paths(oM), b_paths(oM)
        for x, y in zip((*ra, la), (*rb, lb)):
            assert np.abs(np.asarray(x, float) - np.asarray(y, float)).max(initial=0.0) <= 1e-14 * max(
                1.0, float(np.abs(y).max(initial=0.0)))
