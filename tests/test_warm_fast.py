"""The warm path's compiled shortcuts decide exactly what the numpy reference decides.

Every instant of a trajectory runs the scaling decision, the uniqueness test, the runner's answer
check and the wrench outputs; compiled (mcdm_pin/solvers/_fast.py), they must give the numpy code's
decisions (exactly: same thresholds) and values (to rounding: 1e-12 relative). Also: the active
set's KKT solve at a vertex equals the full KKT system's solution, and the iterations the warm
stage reports are its KKT solves (at least one per answer).
"""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, jit
from mcdm_pin import inverse_dynamics as ID
from mcdm_pin import scaling as SC
from mcdm_pin.problem import Context
from mcdm_pin.settings import DEFAULT
from mcdm_pin.solvers import _kkt, _kkt_linalg
from mcdm_pin.solvers import least_norm as LN
from mcdm_pin.solvers.check import project_to_bounds
from mcdm_pin.trajectory import load_trajectory

from .conftest import REPO


@pytest.fixture(scope="module")
def instants():
    """(qp, terms, solution) of every 7th instant of the 2-link arm (cases 1-3, traj1), of the human
    arm's abduct (case 3: a flat optimal face, non-unique first-stage optima) and of the CASPR neck's
    roll (case 3: eight cones, some held)."""
    jit.prepare(policy="wait")
    out = []
    neck = "caspr/8S_neck/8S_neck.yaml"
    for robot_file, traj, cases in (("two_link_sr.yaml", "traj1", (1, 2, 3)), ("human_arm.yaml", "abduct", (2, 3)),
                                    (neck, "roll", (3,))):
        robot = Robot.load(REPO / "robots" / robot_file)
        tr = load_trajectory(robot, traj)
        for case in cases:
            # the neck with the paper's weights and 15 deg cones (benchmarks/_common.py): cones held
            options = {} if robot_file != neck else dict(
                alpha={j: 0.125 for j in robot.joint_names}, beta={j: 0.0 for j in robot.joint_names},
                cones={j: 15.0 for j in robot.joint_names})
            idp = InverseDynamics.for_case(robot, case, **options)
            for k in range(0, len(tr.t), 7):
                terms = idp.evaluate(tr.q[k], tr.qd[k], tr.qdd[k])
                qp = idp.problem.assemble(terms, Context(robot, None))
                out.append((qp, terms, idp.solver.solve(qp), idp))
    return out


def _numpy(fn, *args):
    """``fn(*args)`` with the compiled kernels reported unavailable (the numpy reference path)."""
    saved = jit._READY
    jit._READY = False
    try:
        return fn(*args)
    finally:
        jit._READY = saved


def test_scaling_decision_is_the_numpy_ones(instants):
    for qp, _, _, _ in instants:
        for p in (qp, qp.replace(A=qp.A * 1e5, b=qp.b * 1e5), qp.replace(lb=qp.lb + 1e4, ub=qp.ub + 1e5)):
            compiled = SC.scaling_factors(p)
            reference = _numpy(SC.scaling_factors, p)
            assert (compiled is None) == (reference is None)
            if compiled is not None:
                for a, b in zip((compiled.d, compiled.r, compiled.obj, compiled.cone),
                                (reference.d, reference.r, reference.obj, reference.cone)):
                    np.testing.assert_array_equal(a, b)


def test_scaled_copy_is_the_factors_products_to_the_bit(instants):
    """apply_scaling (one kernel) gives numpy's products of the factors exactly, structured Hessian or
    dense, with or without least-norm weights, with and without cones."""
    seen_cones = set()
    for qp, _, _, _ in instants:
        for p in (qp, qp.replace(P=qp.P), qp.replace(A=qp.A * 1e5, b=qp.b * 1e5)):
            s = SC.scaling_factors(p, force=True)
            d, r, obj = s.d, s.r, s.obj
            out = SC.apply_scaling(p, s)
            np.testing.assert_array_equal(out.A, p.A * d[None, :] * r[:, None])
            np.testing.assert_array_equal(out.b, r * p.b)
            np.testing.assert_array_equal(out.c, d * p.c / obj)
            np.testing.assert_array_equal(out.lb, p.lb / d)
            np.testing.assert_array_equal(out.ub, p.ub / d)
            assert out.r == p.r / obj
            np.testing.assert_array_equal(out.norm_weight, d * d)
            if p.P_factor is not None:  # the structure is scaled, and a dense P only where one was formed
                np.testing.assert_array_equal(out.P_diag, d * p.P_diag * d / obj)
                np.testing.assert_array_equal(out.P_factor, p.P_factor * d[None, :] / np.sqrt(obj))
                assert (out._P is None) == (p._P is None)
            if p._P is not None:
                np.testing.assert_array_equal(out._P, p.P * d[:, None] * (d / obj))
            G0, g0 = p.cone_arrays()[:2]
            G, g = out.cone_arrays()[:2]
            np.testing.assert_array_equal(G, G0 * d[None, None, :] * s.cone[:, None, None])
            np.testing.assert_array_equal(g, s.cone[:, None] * g0)
            for k, cone in enumerate(out.cones):
                np.testing.assert_array_equal(cone.G, G[k])
                assert cone.joint == p.cones[k].joint and cone.angle_deg == p.cones[k].angle_deg
            seen_cones.add(len(p.cones))
            weighted = SC.apply_scaling(p.replace(norm_weight=np.full(p.n, 3.0)), s)
            np.testing.assert_array_equal(weighted.norm_weight, 3.0 * d * d)
    assert 0 in seen_cones and max(seen_cones) >= 8  # the arm's cases 1-2, the neck's eight cones


def test_one_call_scaling_is_the_factors_and_the_copy_to_the_bit(instants):
    """scale_problem (the factors and the copy in one kernel, after the one-pass test) gives exactly
    scaling_factors' factors and apply_scaling's copy, or no scaling where they give none: structured
    or dense Hessian (no structure), forced, with the variables' units given, badly scaled rows."""
    scaled_seen = set()
    for qp, _, _, _ in instants:
        dense = qp.replace(P=qp.P, P_diag=None, P_factor=None)
        for p in (qp, dense, qp.replace(A=qp.A * 1e5, b=qp.b * 1e5), qp.replace(lb=qp.lb + 1e4, ub=qp.ub + 1e5)):
            for f_scale, force, quick in ((None, False, True), (None, True, True), (np.full(p.n, 8.0), False, True),
                                          (None, False, False)):
                out, s = SC.scale_problem(p, f_scale, force, quick)
                ref = SC.scaling_factors(p, f_scale, force)
                assert (s is None) == (ref is None)
                scaled_seen.add(s is not None)
                if s is None:
                    assert out is p
                    continue
                for a, b in zip((s.d, s.r, s.obj, s.cone), (ref.d, ref.r, ref.obj, ref.cone)):
                    np.testing.assert_array_equal(a, b)
                copy = SC.apply_scaling(p, ref)
                for name in ("c", "A", "b", "lb", "ub", "norm_weight", "P_diag", "P_factor", "_P"):
                    a, b = getattr(out, name), getattr(copy, name)
                    assert (a is None) == (b is None), name
                    if a is not None:
                        np.testing.assert_array_equal(a, b)
                assert out.r == copy.r and [c.joint for c in out.cones] == [c.joint for c in copy.cones]
                np.testing.assert_array_equal(out.cone_arrays()[0], copy.cone_arrays()[0])
                np.testing.assert_array_equal(out.cone_arrays()[1], copy.cone_arrays()[1])
    assert scaled_seen == {True, False}


def test_the_one_pass_test_left_to_the_compiled_call_decides_alike():
    """``scale_problem(.., quick=False)`` (what the scaled solver does after a scaled instant) leaves
    the one-pass test for a well-scaled instant to the compiled call, which decides as the test
    before it would: also where the test says "none" although the objective's size at the bounds
    (``ub = 0.01``: ``2 * 0.01^2``) alone would have the factors scale it."""
    from mcdm_pin.qp import QPData

    n = 4
    A = np.array([[1.0, 0.5, 0.0, 0.25], [0.0, 1.0, 1.0, 0.5]])
    qp = QPData(None, np.zeros(n), 0.0, A, np.array([0.005, 0.004]), np.zeros(n), np.full(n, 0.01), [],
                P_diag=np.full(n, 2.0), P_factor=np.zeros((0, n)))
    assert SC.scale_problem(qp) == (qp, None)
    assert SC.scale_problem(qp, quick=False) == (qp, None)
    assert SC.scale_problem(qp, force=True)[1].obj != 1.0  # (the factors alone scale the objective)
    bad = qp.replace(A=A * 1e6, b=qp.b * 1e6)
    (one, s1), (two, s2) = SC.scale_problem(bad), SC.scale_problem(bad, quick=False)
    for a, b in ((s1.d, s2.d), (s1.r, s2.r), (s1.obj, s2.obj), (one.A, two.A), (one.b, two.b), (one.P_diag, two.P_diag)):
        np.testing.assert_array_equal(a, b)


def test_unscaled_answer_is_the_factors_products(instants):
    """Scaling.unscale (one kernel): x = d x_s, y = obj r y_s, z = obj z_s / d and the cones' obj
    cone_k zc_s to the bit, the objective on the original problem (dense or structured Hessian) to
    rounding, NaN where x is not finite, and absent multipliers stay absent."""
    for qp, _, sol, _ in instants:
        for p in (qp, qp.replace(P=qp.P), qp.replace(A=qp.A * 1e5, b=qp.b * 1e5)):
            s = SC.scaling_factors(p, force=True)
            x_s, o = sol.x / s.d, s.obj
            K = len(p.cones)
            scaled = sol.but(x=x_s, y=np.linspace(-1.0, 1.0, len(p.b)), z=np.linspace(0.0, 2.0, p.n),
                             z_cone=np.arange(3.0 * K).reshape(K, 3))
            out = s.unscale(p, scaled)
            np.testing.assert_array_equal(out.x, s.d * x_s)
            np.testing.assert_array_equal(out.y, o * s.r * scaled.y)
            np.testing.assert_array_equal(out.z, o * scaled.z / s.d)
            np.testing.assert_array_equal(out.z_cone, o * s.cone[:, None] * scaled.z_cone)
            ref = p.objective(out.x)
            assert abs(out.objective - ref) <= 1e-13 * max(1.0, abs(ref))
            bare = s.unscale(p, scaled.but(y=None, z=None, z_cone=None, x=np.full(p.n, np.nan)))
            assert bare.y is None and bare.z is None and bare.z_cone is None and np.isnan(bare.objective)


def test_uniqueness_decision_is_the_numpy_ones(instants):
    seen = set()
    for qp, _, sol, _ in instants:
        assert sol.status == "optimal"
        decided = LN.is_unique(qp, sol)
        assert decided == _numpy(LN.is_unique, qp, sol)
        seen.add(decided)
    assert seen == {True, False}  # both answers occur (the human arm's case 2/3 optimum is a face)


def test_the_least_norm_face_is_the_numpy_one(instants):
    """The least-norm stage's face in one compiled pass (``least_norm._face``: the compiled uniqueness
    test's strongly active set, the face's rows, their basis) against numpy: ``_strongly_active``'s
    free variables and held cones, and the span of the face's rows (the objective's rows of curvature
    above 1e-12 of the largest, the equations, ``c`` and the held cones' rows, each normalised, on the
    coordinates that are not unit rows) by one numpy SVD; and the least-norm problem's bounds and rows
    made in the same pass equal their numpy formulas."""
    held_seen = 0
    for qp, _, sol, _ in instants:
        if sol.z is None or qp.strictly_convex():
            continue
        free, held, S, rest, Vt, lb, ub, E = LN._face(qp, sol, DEFAULT)[:8]
        lb_ref, ub_ref = np.where(free, qp.lb, -np.inf), np.where(free, qp.ub, np.inf)
        lb_ref[S] = ub_ref[S] = sol.x[S]
        E_ref = np.zeros((len(Vt), qp.n))
        E_ref[:, rest] = Vt
        np.testing.assert_array_equal(lb, lb_ref)
        np.testing.assert_array_equal(ub, ub_ref)
        np.testing.assert_array_equal(E, E_ref)
        free_ref, cone_rows, _ = LN._strongly_active(qp, sol, DEFAULT, curvature=False)
        np.testing.assert_array_equal(free, free_ref)
        assert set(np.flatnonzero(held)) == {k for k, _ in cone_rows}
        held_seen += int(held.sum())
        F, d = qp.P_factor, qp.P_diag
        curv = (F * F).sum(axis=1)
        top = max(curv.max(initial=0.0), np.abs(d).max(initial=0.0), 1e-300)
        unit = (np.abs(d) > 1e-12 * top) | ~free_ref
        np.testing.assert_array_equal(S, np.flatnonzero(unit))
        np.testing.assert_array_equal(rest, np.flatnonzero(~unit))
        rows = [F[curv > 1e-12 * top], qp.A, qp.c[None, :]] + [r[None, :] for _, r in cone_rows]
        N = np.vstack(rows)
        N = N[np.linalg.norm(N, axis=1) > 0]
        N = (N / np.linalg.norm(N, axis=1)[:, None])[:, rest]
        if N.size:
            _, sv, ref = np.linalg.svd(N, full_matrices=False)
            ref = ref[sv > 1e-10 * max(sv.max(), 1.0)]
        else:
            ref = np.zeros((0, len(rest)))
        assert Vt.shape == ref.shape
        np.testing.assert_allclose(Vt @ Vt.T, np.eye(len(Vt)), atol=1e-12)
        np.testing.assert_allclose(ref @ Vt.T @ Vt, ref, atol=1e-9)  # the same space
    assert held_seen > 0  # the neck's case 3 holds cones


def _face_frames(robot_file, traj, case, every=1):
    """(qp, first-stage answer, face, the least-norm stage's chain) at the instants of ``traj`` whose
    first-stage optimum is not proven unique (the least-norm stage's work)."""
    jit.prepare(policy="wait")
    robot = Robot.load(REPO / "robots" / robot_file)
    tr = load_trajectory(robot, traj)
    idp = InverseDynamics.for_case(robot, case)
    stage = next(s for s in idp.solver.inner.stages if isinstance(s, LN.LeastNorm))
    seen = []
    run = stage.run

    def spy(qp, sol, deadline):  # the first stage's answer as the least-norm stage receives it
        if sol.unique is None and not (not sol.unique_tested and LN.is_unique(qp, sol, DEFAULT)):
            seen.append((qp, sol, LN._face(qp, sol, DEFAULT), stage.inner))
        return run(qp, sol, deadline)

    stage.run = spy
    f = None
    for k in range(0, len(tr.t), every):
        f = idp.solve(tr.q[k], tr.qd[k], tr.qdd[k], f_prev=f).f
    return seen


@pytest.mark.parametrize("robot_file, traj, case, expect", [("myosuite/myoarm.yaml", "abduction", 3, "all"),
                                                            ("myosuite/myoelbow.yaml", "flexion", 2, "all"),
                                                            ("human_arm.yaml", "abduct", 2, "all"),
                                                            ("human_arm.yaml", "abduct", 3, "all"),
                                                            ("caspr/SpiderBot_UR3/SpiderBot_UR3.yaml", "x", 2, "all")])
def test_the_faces_least_norm_point_is_the_least_norm_problems_answer(robot_file, traj, case, expect):
    """The least-norm stage answers with the face's own least-norm point (``Face.direct``: the
    problem in the face's free directions, its bounds by an active set) wherever no cone left out
    of that problem breaks there: on these robots at every least-norm instant (MyoSuite's arm and
    elbow: faces of one or two directions; SpiderBot and the human arm: two and three, with bounds
    that bind; the human arm's case 3 with its cone not held at a third of them, met along the
    face). The point equals the least-norm problem's optimum as the stage's chain solves it (with
    its bounds and cones) to 1e-12 of the largest force, keeps the bounds exactly and lies on the
    face (the same ``E x``, the pinned coordinates unmoved)."""
    frames = _face_frames(robot_file, traj, case, every=3)
    assert frames
    direct = 0
    for qp, sol, face, inner in frames:
        out = inner.solve(LN.stage2_problem(qp, sol, DEFAULT, face), hint=sol)
        assert out.status == "optimal"
        x_chain = project_to_bounds(qp, out, DEFAULT).x
        if not face.direct:
            assert not face.held.all()  # (only a cone left out stops it on these robots)
            continue
        direct += 1
        x = face.x
        scale = max(np.abs(x_chain).max(), 1e-300)
        assert np.abs(x - x_chain).max() <= 1e-12 * scale
        assert np.all(x >= qp.lb) and np.all(x <= qp.ub)
        np.testing.assert_array_equal(x[face.S], sol.x[face.S])
        np.testing.assert_allclose(face.E @ x, face.E @ sol.x, rtol=0, atol=1e-12 * scale)
        w = LN._norm_weight(qp)
        assert w @ x**2 <= w @ sol.x**2 * (1 + 1e-12)  # no farther from the origin than the first stage's
    assert direct == len(frames) if expect == "all" else 0 < direct < len(frames)


def test_the_least_norm_stage_answers_alike_by_the_face_and_by_its_chain(monkeypatch):
    """Along the human arm's ``abduct`` (case 3: every instant a face of optima, bounds that bind,
    the cone not held at some), the least-norm stage with the face's own point and with it switched
    off (the chain answering every time) gives the same forces to 1e-12 and the same statuses."""
    jit.prepare(policy="wait")
    robot = Robot.load(REPO / "robots" / "human_arm.yaml")
    tr = load_trajectory(robot, "abduct")
    direct = InverseDynamics.for_case(robot, 3).solve_trajectory(tr, progress=False)
    face = LN._face
    monkeypatch.setattr(LN, "_face", lambda *a: face(*a)._replace(direct=False))
    chain = InverseDynamics.for_case(robot, 3).solve_trajectory(tr, progress=False)
    assert list(direct.status) == list(chain.status) and all(s == "optimal" for s in direct.status)
    assert np.abs(direct.f - chain.f).max() <= 1e-12 * np.abs(chain.f).max()


def test_the_least_norm_problem_keeps_the_cones_not_held_as_stacked_afresh(instants):
    """Where some cones are held on the optimal face and others not, the least-norm problem takes the
    others' stacked arrays and constants from the problem's (``stage2_problem``), and they equal
    those stacked afresh from its cones. The human arm's answers hold its one cone: a second, wide
    cone on the same joint (85 deg, not binding) is added to each problem and solved again."""
    from mcdm_pin.qp import ConeData, QPData

    partial = 0
    for qp, _, _, idp in instants:
        if len(qp.cones) != 1 or qp.strictly_convex():
            continue
        c = qp.cones[0]
        wide = ConeData("wide", c.G, c.g, c.axis, 85.0, c.basis)
        qp2 = qp.with_cones([c, wide])
        sol = idp.solver.fresh().solve(qp2)
        if sol.status != "optimal" or sol.z is None or not LN._face(qp2, sol, DEFAULT).held[0]:
            continue
        p = LN.stage2_problem(qp2, sol, DEFAULT)
        assert [k.joint for k in p.cones] == ["wide"]
        fresh = QPData(p.P, p.c, p.r, p.A, p.b, p.lb, p.ub, p.cones)
        for got, want in zip(p.cone_arrays() + p.cone_consts()[1:], fresh.cone_arrays() + fresh.cone_consts()[1:]):
            np.testing.assert_array_equal(got, want)
        assert p.cone_consts()[0] == fresh.cone_consts()[0] == ("wide",)
        partial += 1
    assert partial > 0


def _exact_unique(H, J, thr):
    """The exact test the shortcut stands in for: the smallest eigenvalue of H on null(J) above thr."""
    _, s, Vt = np.linalg.svd(J, full_matrices=True)
    Z = Vt[int((s > 1e-10 * s.max()).sum()):].T
    return Z.shape[1] == 0 or np.linalg.eigvalsh(Z.T @ H @ Z).min() > thr


def test_uniqueness_shortcut_only_claims_what_the_null_space_test_proves():
    """``H + gamma J^T J - thr I`` definite (least_norm's shortcut, compiled and numpy) implies the
    exact test's "unique", on random problems with free directions left (more columns than rows):
    definite Hessians (both say unique), Hessians singular on null(J) (neither may: the shortcut
    must fail) and Hessians whose only null directions the rows see (the shortcut decides)."""
    from mcdm_pin.solvers import _unique

    rng = np.random.default_rng(3)
    claimed = {True: 0, False: 0}
    for trial in range(300):
        nf = int(rng.integers(3, 30))
        rows = int(rng.integers(1, nf))  # fewer rows than free variables: a null space of nf - rows
        J = rng.standard_normal((rows, nf)) * 10.0 ** rng.uniform(-3, 3)
        kind = trial % 3
        if kind == 0:  # positive definite
            X = rng.standard_normal((nf, nf + 2))
            H = X @ X.T
        elif kind == 1:  # singular on null(J): a null direction of J that H does not see
            z = np.linalg.svd(J)[2][-1]
            X = rng.standard_normal((nf, nf))
            X -= np.outer(X @ z, z)  # X z = 0
            H = X.T @ X
        else:  # H's null space seen by J: H = F^T F with [F; J] of full column rank
            F = rng.standard_normal((nf - rows, nf))
            H = F.T @ F
        H *= 10.0 ** rng.uniform(-4, 4)
        hscale = float(np.abs(H).max())
        thr, penalty = DEFAULT.unique_rel * hscale, DEFAULT.unique_penalty
        exact = _exact_unique(H, J, thr)
        compiled = bool(_unique.definite_beyond(np.ascontiguousarray(H), np.ascontiguousarray(J), rows, thr, hscale,
                                                penalty))
        reference = LN._definite_beyond(H, J, thr, hscale, penalty)
        assert compiled == reference
        if compiled:
            assert exact  # never "unique" where the null space test would not say so
        if kind == 1:
            assert not compiled and not exact
        claimed[compiled] += 1
    assert claimed[True] >= 150  # and it decides the definite cases (kinds 0 and 2)


def test_answer_check_and_outputs_equal_the_numpy_ones(instants):
    for qp, terms, sol, idp in instants:
        m = idp.robot.m
        (s1, eom1), (s2, eom2) = ID._check(qp, terms, sol, m, DEFAULT), _numpy(ID._check, qp, terms, sol, m, DEFAULT)
        assert s1.status == s2.status and s1.message == s2.message
        # the residual of an exact answer is itself rounding (~1e-16): the order of the sums decides
        # its digits; anything that matters (the check's 1e-8) is far above 1e-14
        assert eom1 == pytest.approx(eom2, rel=1e-9, abs=1e-14)
        reference = _numpy(ID._outputs, terms, sol.x[:m], len(idp.robot.joints))
        s3, eom3, fused = ID._check(qp, terms, sol, m, DEFAULT, with_outputs=True)  # the runner's one pass
        assert s3.status == s1.status and s3.message == s1.message and eom3 == eom1
        for outputs in (ID._outputs(terms, sol.x[:m], len(idp.robot.joints)), fused):
            for a, b in zip(outputs, reference):
                np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(b).max()))
    # a broken answer is reported by both paths with the same message
    qp, terms, sol, idp = instants[0]
    bad = sol.but(x=sol.x + 1.0)
    assert ID._check(qp, terms, bad, idp.robot.m, DEFAULT)[0].message == \
        _numpy(ID._check, qp, terms, bad, idp.robot.m, DEFAULT)[0].message != ""


def test_kkt_check_is_the_numpy_ones(instants):
    """The answer check's KKT residuals (the check stage, on every answer no active set verified),
    compiled and in numpy: dense and structured Hessians, cones held and not, with and without duals,
    a constant objective (the gradient floor), answers moved off their optimum and a NaN. Values to
    rounding (the order of the sums differs), the same problems reported."""
    from mcdm_pin.solvers import check as CK
    from mcdm_pin.solvers.base import Solution

    rng = np.random.default_rng(3)
    cases = []
    for qp, terms, sol, idp in instants:
        cases += [(qp, sol), (qp, sol.but(y=None, z=None, z_cone=None)),
                  (qp, sol.but(x=sol.x * (1.0 + 1e-6 * rng.standard_normal(qp.n)))),
                  (qp, sol.but(z=None if sol.z is None else sol.z + 1e-3 * np.abs(sol.z).max()))]
        if qp.P_diag is not None:  # the same problem with its Hessian dense
            cases.append((qp.replace(P=qp.P.copy()), sol))
    qp = instants[0][0]
    flat = qp.replace(P=None, P_diag=np.zeros(qp.n), P_factor=np.zeros((0, qp.n)), c=np.zeros(qp.n))
    x = np.linalg.lstsq(flat.A, flat.b, rcond=None)[0]
    cases += [(flat, Solution(x, "optimal", y=np.zeros(len(flat.b)), z=np.zeros(flat.n), z_cone=np.zeros((0, 3)))),
              (qp, instants[0][2].but(x=np.full(qp.n, np.nan)))]
    assert any(c[0].structured for c in cases) and any(not c[0].structured for c in cases)
    assert any(c[0].cones for c in cases) and any(c[1].z is None for c in cases)
    for qp, sol in cases:
        got, ref = CK.kkt_residuals(qp, sol), _numpy(CK.kkt_residuals, qp, sol)
        assert got.keys() == ref.keys()
        for key in ref:
            if np.isnan(ref[key]):
                assert np.isnan(got[key]), key
            else:
                # (a cone's violation is an angle of ~15 deg less its half-angle: 1e-14 deg of rounding)
                assert got[key] == pytest.approx(ref[key], rel=1e-9, abs=1e-12 if key == "cone_deg" else 1e-14), key
        assert CK.kkt_problems(qp, sol) == _numpy(CK.kkt_problems, qp, sol)


def test_vertex_solve_is_the_kkt_systems_solution():
    rng = np.random.default_rng(3)
    for nf in (1, 4, 25):
        R = rng.standard_normal((nf, nf))
        H = rng.standard_normal((nf, nf))
        H = H @ H.T
        K = np.block([[H, R.T], [R, np.zeros((nf, nf))]])
        rhs = rng.standard_normal(2 * nf)
        want = np.linalg.solve(K, rhs)
        got = _kkt_linalg.vertex_solve(K, rhs, nf, True)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * np.abs(want).max())
    # a singular R: the fallback (least squares) gives NaN for an inconsistent system, as before
    K = np.zeros((4, 4))
    K[:2, :2] = np.eye(2)
    got = _kkt_linalg.vertex_solve(K, np.ones(4), 2, True)
    assert not np.all(np.isfinite(got))


def test_warm_stage_counts_its_kkt_solves(instants):
    robot = Robot.load(REPO / "robots" / "two_link_sr.yaml")
    run = InverseDynamics.for_case(robot, 3).solve_trajectory(load_trajectory(robot, "traj1"), progress=False)
    warm = run.stage == "warm_active_set"
    assert warm.sum() > 90
    assert run.iterations[warm].min() >= 1  # every answer solved at least one KKT system
    from mcdm_pin.cli.solve import stage_counts

    line = stage_counts(run)
    assert line.startswith(f"answered by warm_active_set at {warm.sum()} instants (median ")
    assert "KKT solves" in line


def test_cone_batch_is_the_numpy_ones(instants):
    seen = 0
    for qp, terms, _, idp in instants:
        batch = idp.problem._plan["cones"]
        if batch is None:
            continue
        seen += 1
        compiled = batch(terms)[1]
        for a, b in zip(compiled, batch.arrays(terms) + (batch.tan, batch.basis0)):
            np.testing.assert_allclose(a, b, rtol=1e-14, atol=1e-14 * np.abs(b).max())
        assert qp.cone_consts()[0] == tuple(c.joint for c in qp.cones)
        np.testing.assert_array_equal(qp.cone_consts()[1], [c.angle_deg for c in qp.cones])
    assert seen > 10


def _reference_try(qp, guess, max_pivots):
    """:func:`try_active_set` as it was before its compiled answer: the kernel, then the numpy
    :func:`active_solution`."""
    from mcdm_pin.solvers import active_set as AS

    G, gc, ax, tn, basis0 = qp.cone_arrays()
    state = guess.cable_state(qp.n)
    names = [c.joint for c in qp.cones]
    cact = np.array([nm in guess.cones for nm in names], dtype=np.bool_)
    cdir = basis0.copy()
    for k in np.flatnonzero(cact):
        cdir[k] = guess.cones[names[k]][0]
    x0, mus0 = guess.point_guess(qp)
    run = _kkt.active_set_run(AS.kernel_qp(qp), AS.kernel_cones(qp), state, cact, cdir,
                              AS.kernel_limits(DEFAULT, max_pivots), np.ascontiguousarray(x0), np.ascontiguousarray(mus0))
    if run.code != _kkt.FOUND:
        return None
    return AS.active_solution(qp, run.f, run.y, run.grad, run.state, run.cact, run.mus, run.dirs, run.next_state,
                              iterations=int(run.solves))


def test_warm_answer_is_the_numpy_ones(instants):
    """The compiled answer of the active-set stage (kernel, duals, objective, next guess) equals the
    kernel's point converted by the numpy code, from guesses near (the previous sampled instant's
    answer) and far (no bound, no cone held)."""
    from mcdm_pin.solvers.active_set import ActiveSet, try_active_set

    found = held = uniques = 0
    prev = None
    for qp, _, sol, idp in instants:
        guesses = [ActiveSet(np.zeros(0, int), np.zeros(0, int))]
        if prev is not None and prev[1] is idp and prev[0].active is not None:
            guesses.append(prev[0].active)
        prev = (sol, idp)
        for guess in guesses:
            got, want = try_active_set(qp, guess, 50), _reference_try(qp, guess, 50)
            assert (got is None) == (want is None)
            if got is None:
                continue
            found += 1
            np.testing.assert_array_equal(got.x, want.x)
            np.testing.assert_array_equal(got.y, want.y)
            np.testing.assert_array_equal(got.z, want.z)
            scale = max(1.0, np.abs(want.z_cone).max(initial=0.0))
            np.testing.assert_allclose(got.z_cone, want.z_cone, rtol=1e-14, atol=1e-14 * scale)
            assert got.objective == pytest.approx(want.objective, rel=1e-12, abs=1e-12)
            assert got.iterations == want.iterations and got.verified and got.status == want.status
            # the uniqueness decided in the same call is the least-norm stage's numpy decision
            assert got.unique == (True if _numpy(LN.is_unique, qp, want) else None)
            uniques += bool(got.unique)
            np.testing.assert_array_equal(got.active.state, want.active.state)
            assert got.active.cones.keys() == want.active.cones.keys()
            for name, (d, mu) in want.active.cones.items():
                np.testing.assert_array_equal(got.active.cones[name][0], d)
                assert got.active.cones[name][1] == mu
                held += 1
            # the next guess's arrays say what its dictionary says
            mask, dirs = got.active.cone_guess(qp)
            assert [c.joint for k, c in enumerate(qp.cones) if mask[k]] == list(want.active.cones)
    assert found > 20 and held > 0
    # both decisions occur: the human arm's abduct has a flat optimal face (not unique)
    assert 0 < uniques < found, (uniques, found)


def test_interaction_quadratic_is_the_numpy_ones(instants):
    from mcdm_pin.objectives import MinInteractions

    seen = 0
    for _, terms, _, idp in instants:
        obj = idp.problem.objective
        if not isinstance(obj, MinInteractions):
            continue
        seen += 1
        compiled = obj.quadratic(terms, None)
        reference = _numpy(obj.quadratic, terms, None)
        for a, b in ((compiled.P, reference.P), (compiled.c, reference.c), (compiled.factor, reference.factor),
                     (compiled.diag, reference.diag)):
            np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-13 * max(np.abs(b).max(initial=0.0), 1e-300))
        assert compiled.r == pytest.approx(reference.r, rel=1e-13, abs=1e-300)
        np.testing.assert_array_equal(compiled.P, compiled.P.T)
    assert seen > 10


def test_projection_decision_is_the_numpy_ones(instants):
    from mcdm_pin.solvers.check import project_to_bounds

    for qp, _, sol, _ in instants:
        for x in (sol.x, np.clip(sol.x - 1e-13, qp.lb, None), sol.x + 1e-3, np.full(qp.n, np.nan)):
            s = sol.but(x=x)
            a, b = project_to_bounds(qp, s), _numpy(project_to_bounds, qp, s)
            np.testing.assert_array_equal(a.x, b.x)


def test_ratio_test_with_the_vertex_factors_is_the_fresh_ones():
    """The dual simplex step's ratio test reuses the vertex solve's LU of the free columns (the same
    matrix): the same entering cable as solving that matrix afresh."""
    from mcdm_pin.solvers._structs import QP, Cones

    rng = np.random.default_rng(5)
    n, neq = 12, 5
    for _ in range(50):
        A = rng.standard_normal((neq, n))
        state = np.ones(n, dtype=np.int8)
        state[rng.choice(n, neq, replace=False)] = 0
        state[(state != 0) & (rng.random(n) < 0.3)] = 2
        free = np.flatnonzero(state == 0)
        grad = rng.standard_normal(n)
        LU, perm, ok = _kkt_linalg.lu_factor(np.ascontiguousarray(A[:, free]))
        assert ok
        z3 = np.zeros((0, 3))
        qp = QP(np.zeros((n, n)), np.zeros(0), np.zeros((0, n)), np.zeros(n), 0.0, A, np.zeros(neq), np.zeros(n),
                np.full(n, 1.0), False)
        cones = Cones(np.zeros((0, 3, n)), z3, z3, np.zeros(0), z3, np.zeros(0), np.zeros((0, 2, 3)))
        for kind in (1, 2):
            r = int(free[rng.integers(neq)])
            args = (qp, cones, np.zeros(0, dtype=np.bool_), z3, state, grad, kind, r, 0)
            assert _kkt._ratio_test(*args, LU, perm, True) == \
                _kkt._ratio_test(*args, np.zeros((0, 0)), np.zeros(0, dtype=np.int64), False)


def test_terms_read_back_through_views_follow_every_state():
    """The evaluator reads Pinocchio's joint wrenches through views of its own data made once: at
    every state they equal a computation in fresh data."""
    from mcdm_pin.model.terms import TermsEvaluator

    robot = Robot.load(REPO / "robots" / "caspr" / "8S_neck" / "8S_neck.yaml")
    tr = load_trajectory(robot, "roll")
    ev = TermsEvaluator(robot, compiled=jit.ready())
    for k in range(0, len(tr.t), 10):
        own = ev(tr.q[k], tr.qd[k], tr.qdd[k])
        fresh = ev(tr.q[k], tr.qd[k], tr.qdd[k], data=robot.model.createData())
        np.testing.assert_array_equal(own.u, fresh.u)
        np.testing.assert_array_equal(own.RT, fresh.RT)


def test_ipm_answer_is_the_numpy_ones(instants):
    """The interior-point stage's compiled call (cone rows, method, duals, objective, next guess:
    :func:`mcdm_pin.solvers._fast.ipm_answer`) equals the method run on the numpy cone rows
    (:meth:`QPData.cone_rows`) with its crossover point converted by the numpy
    :func:`active_solution`: the same point (the cone rows agree to rounding, and the crossover
    lands on the same active set), duals and guess."""
    from mcdm_pin.solvers import _ipm
    from mcdm_pin.solvers import active_set as AS
    from mcdm_pin.solvers.ipm import ipm_arguments, ipm_solve

    crossed = cones_held = 0
    for qp, _, _, _ in instants:
        got = ipm_solve(qp)
        kqp, cones, limits = ipm_arguments(qp)
        T, t = qp.cone_rows()
        c_ = np.ascontiguousarray
        code, x, y, z, zc, it, state, cact, mus, dirs = _ipm.ipm_solve(kqp, c_(T), c_(t), cones, limits)
        assert got.iterations == it
        if code != _ipm.CROSSOVER:
            assert got.active is None
            continue
        crossed += 1
        grad = -z
        thr = 1e-12 * max(np.abs(grad).max(initial=0.0), 1e-300)
        nxt = state.copy()
        nxt[((state == 1) & ~(grad > thr)) | ((state == 2) & ~(grad < -thr))] = 0
        want = AS.active_solution(qp, x, y, grad, state, cact, mus, dirs, nxt, iterations=int(it), stage="ipm")
        scale = max(1.0, np.abs(want.x).max())
        np.testing.assert_allclose(got.x, want.x, rtol=1e-12, atol=1e-12 * scale)
        np.testing.assert_allclose(got.z, want.z, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(want.z).max()))
        zscale = max(1.0, np.abs(want.z_cone).max(initial=0.0))
        np.testing.assert_allclose(got.z_cone, want.z_cone, rtol=1e-9, atol=1e-9 * zscale)
        assert got.objective == pytest.approx(want.objective, rel=1e-12, abs=1e-12)
        np.testing.assert_array_equal(got.active.state, want.active.state)
        assert got.active.cones.keys() == want.active.cones.keys()
        cones_held += len(want.active.cones)
        assert got.unique == (True if _numpy(LN.is_unique, qp, want) else None)
    assert crossed > 20 and cones_held > 0, (crossed, cones_held)


def test_folded_cones_give_the_expanded_systems_directions(instants):
    """The interior-point method's Newton directions with the neck's cones folded into their joints'
    force groups (:func:`mcdm_pin.solvers._ipm_newton._fold_factor`: a 48 x 48 system instead of
    72 x 72) equal those of the expanded system, to 1e-9 relative, for scalings from far off the
    cones (W^2 of order one) to a cone held at a gap of 1e-10 (W^2 of order 1e-10 in one direction)."""
    from mcdm_pin.solvers import _fast, _ipm_direction
    from mcdm_pin.solvers import _ipm_newton as la
    from mcdm_pin.solvers._ipm_structure import structure
    from mcdm_pin.solvers._structs import NewtonSystem
    from mcdm_pin.solvers.ipm import ipm_arguments

    rng = np.random.default_rng(7)
    folded = 0
    for qp, _, _, _ in instants:
        if len(qp.cones) != 8:
            continue
        kqp, cones, limits = ipm_arguments(qp)
        d0, F, A = kqp.d0, kqp.F, kqp.A
        T, t = _fast.cone_rows(cones.G, cones.gc, cones.ax, cones.cosr, cones.basis)
        B, rf, M0inv, Ct, cg, fold = structure(F, T, A, limits.rank_tol)
        assert fold[0].shape[0] == 8  # every cone folded into its joint's group
        none = (np.empty((0, 3, 3)), np.empty(0, dtype=np.int64), np.empty((0, 3, 3)), np.empty((0, 3, 3)))
        n, K, neq = len(d0), 8, A.shape[0]
        for gap in (1.0, 1e-4, 1e-10):
            # a cone scaling from interior points s, z whose product approaches the boundary
            W2 = np.zeros((K, 3, 3))
            for k in range(K):
                s = np.array([1.0, *(rng.uniform(-1, 1, 2) * (1 - gap) / np.sqrt(2))])
                z = np.array([1.0, *(-s[1:])]) * rng.uniform(0.5, 2.0)
                _ipm_direction._soc_scaling(s, z, np.zeros((3, 3)), np.zeros((3, 3)), W2[k], np.zeros(3))
            dinv = 1.0 / rng.uniform(1e-3, 1e3, n)
            r1, r2, r3 = rng.standard_normal(n), rng.standard_normal(neq), rng.standard_normal((K, 3))
            out = []
            for fd, p in ((fold, rf + neq), (none, rf + 3 * K + neq)):
                Km = np.empty((p, p))
                Kb = Km if fd[0].shape[0] else np.empty((B.shape[0], B.shape[0]))
                gram = la.gram_plan(B, n)
                la.factor(gram, rf, M0inv, Ct, cg, fd, W2, dinv, 1e-14, np.empty((2, B.shape[1])), Kb, Km,
                          np.empty((rf, rf)), np.empty((3 * K, rf)))
                dx, dy, dzc = np.empty(n), np.empty(neq), np.empty((K, 3))
                la.solve(NewtonSystem(B, rf, Ct, cg, fd, Km, F, T, A, gram), dinv, r1, r3, r2, np.empty(n), np.empty(p),
                         np.empty(rf), dx, dy, dzc)
                out.append((dx, dy, dzc))
            for got, want in zip(out[0], out[1]):
                np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
        folded += 1
    assert folded >= 10, folded


def test_a_warm_start_that_fails_halves_the_next_instants_pivot_limit(monkeypatch):
    """WarmActiveSet: after a failure the next limit is half the last, down to warm_min_pivots; an
    answer, or a reset, restores warm_max_pivots (the answer itself is the chain's either way)."""
    from mcdm_pin.solvers import active_set

    limits, answers = [], []
    monkeypatch.setattr(jit, "ready", lambda: True)
    monkeypatch.setattr(active_set, "try_active_set",
                        lambda qp, guess, max_pivots, stage, settings: limits.append(max_pivots) or answers.pop(0))
    stage = active_set.WarmActiveSet(DEFAULT.replace(warm_max_pivots=50, warm_min_pivots=4))
    stage.guess = object()
    answers += [None] * 5 + ["found", None]
    for _ in range(7):
        stage.run(None, None, None)
    assert limits == [50, 25, 12, 6, 4, 4, 50]
    stage.reset()
    assert stage.max_pivots == 50


def test_a_failed_warm_start_near_its_answer_keeps_the_whole_pivot_limit(monkeypatch):
    """WarmActiveSet: where the instant's answer lies within ``warm_max_pivots`` bound and cone
    changes of the guess that failed, the instants do not jump, and the next one gets the whole
    limit; an answer further off leaves it halved (a run of far-apart instants)."""
    from mcdm_pin.qp import QPData
    from mcdm_pin.solvers import active_set
    from mcdm_pin.solvers.base import Solution

    n = 12
    qp = QPData(np.eye(n), np.zeros(n), 0.0, np.ones((1, n)), np.ones(1), np.zeros(n), np.ones(n))
    monkeypatch.setattr(jit, "ready", lambda: True)
    monkeypatch.setattr(active_set, "try_active_set", lambda *a, **k: None)
    state = np.zeros(n, dtype=np.int8)
    for moved, limit in ((3, 8), (8, 8), (9, 4)):  # changes between the failed guess and the answer
        stage = active_set.WarmActiveSet(DEFAULT.replace(warm_max_pivots=8, warm_min_pivots=2, warm_dual_steps=0))
        stage.guess = active_set.ActiveSet(np.zeros(0, int), np.zeros(0, int), state=state.copy())
        assert stage.run(qp, None, None) is None and stage.max_pivots == 4
        answer = state.copy()
        answer[:moved] = 1
        answer[0] = 2  # (another bound counts as a change too)
        stage.learn(qp, Solution(x=np.zeros(n), status="optimal",
                                 active=active_set.ActiveSet(np.zeros(0, int), np.zeros(0, int), state=answer)))
        assert active_set.changes(qp, active_set.ActiveSet(np.zeros(0, int), np.zeros(0, int), state=state),
                                  stage.guess) == moved
        assert stage.max_pivots == limit, (moved, stage.max_pivots)
