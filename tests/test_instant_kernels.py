"""Per-instant kernels of the musculoskeletal path: the muscle curves (mcdm_pin/model/muscle_kernels.py),
Ruiz equilibration (mcdm_pin.model.kernels.ruiz) and the couplings' basis
(mcdm_pin.model.coupling_kernels.coupling_basis): compiled and uncompiled give the same bits, and both equal
independent formulations written here (MuJoCo's curves, as ``mcdm_pin/model/muscles.py``'s
docstring gives them; Ruiz's sweeps as ``mcdm_pin/scaling.py``'s; the basis by finite differences
of the couplings' fill). The muscle forces themselves are checked against MuJoCo's
``actuator_force`` in tests/test_muscles.py, the basis in tests/test_couplings.py."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import jit
from mcdm_pin.model import muscles as mu

EPS = mu.MINVAL


def _params(m: int = 40, seed: int = 3) -> mu.MuscleParams:
    """Muscles with MuJoCo's default curve shapes and varied ranges, gears and forces (two with a
    passive side of their own, as myoarm_r's SUPSP; one with a narrowed activation range)."""
    rng = np.random.default_rng(seed)
    r0 = rng.uniform(0.5, 0.8, m)
    rng_ = np.stack([r0, r0 + rng.uniform(0.4, 0.8, m)], axis=1)
    bias = rng_.copy()
    bias[:2] += [0.05, 0.1]
    lr0 = rng.uniform(0.1, 0.3, m)
    act_min = np.zeros(m)
    act_min[3] = 0.01
    return mu.MuscleParams(
        names=[f"m{i}" for i in range(m)], range=rng_, force=rng.uniform(50, 2000, m), scale=np.full(m, 200.0),
        lmin=rng.uniform(0.3, 0.6, m), lmax=rng.uniform(1.4, 1.8, m), vmax=rng.uniform(1.0, 10.0, m),
        fpmax=rng.uniform(0.5, 1.5, m), fvmax=rng.uniform(1.2, 1.6, m), bias_range=bias,
        bias_force=rng.uniform(50, 2000, m), bias_lmax=rng.uniform(1.4, 1.8, m),
        lengthrange=np.stack([lr0, lr0 + rng.uniform(0.05, 0.2, m)], axis=1), gear=rng.uniform(0.5, 2.0, m),
        ctrlrange=np.tile([-np.inf, np.inf], (m, 1)), actrange=np.tile([-np.inf, np.inf], (m, 1)),
        act_min=act_min, act_max=np.ones(m))


def _states(p: mu.MuscleParams, n: int = 200, seed: int = 4):
    """Tendon lengths over the whole length range and beyond, and speeds that reach every piece of
    F_V (shortening faster than vmax included)."""
    rng = np.random.default_rng(seed)
    lo, hi = p.lengthrange[:, 0] / p.gear, p.lengthrange[:, 1] / p.gear
    ell = rng.uniform(lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo), (n, p.size))
    speed = p.optimal_length * p.vmax / p.gear  # tendon speed at |v| = 1
    ell_dot = speed * rng.uniform(-1.5, 1.5, (n, p.size))
    return ell, ell_dot


def _reference(p: mu.MuscleParams, ell, ell_dot):
    """``(passive, gain)`` from the formulas, numpy, piece by piece (np.select)."""
    L, V = p.gear * ell, p.gear * ell_dot
    lopt = (p.lengthrange[:, 1] - p.lengthrange[:, 0]) / np.maximum(EPS, p.range[:, 1] - p.range[:, 0])
    lopt_p = (p.lengthrange[:, 1] - p.lengthrange[:, 0]) / np.maximum(EPS, p.bias_range[:, 1] - p.bias_range[:, 0])
    l = p.range[:, 0] + (L - p.lengthrange[:, 0]) / np.maximum(EPS, lopt)
    v = V / np.maximum(EPS, lopt * p.vmax)
    lp = p.bias_range[:, 0] + (L - p.lengthrange[:, 0]) / np.maximum(EPS, lopt_p)
    a, b = 0.5 * (p.lmin + 1), 0.5 * (1 + p.lmax)
    FL = np.select([(l < p.lmin) | (l > p.lmax), l <= a, l <= 1, l <= b],
                   [0.0, 0.5 * ((l - p.lmin) / (a - p.lmin)) ** 2, 1 - 0.5 * ((1 - l) / (1 - a)) ** 2,
                    1 - 0.5 * ((l - 1) / (b - 1)) ** 2], 0.5 * ((p.lmax - l) / (p.lmax - b)) ** 2)
    y = p.fvmax - 1
    FV = np.select([v <= -1, v <= 0, v <= y], [0.0, (v + 1) ** 2, p.fvmax - (y - v) ** 2 / y], p.fvmax)
    bp = 0.5 * (1 + p.bias_lmax)
    FP = np.select([lp <= 1, lp <= bp], [0.0, 0.5 * p.fpmax * ((lp - 1) / (bp - 1)) ** 2],
                   p.fpmax * (0.5 + (lp - bp) / (bp - 1)))
    return p.gear * p.bias_force * FP, p.gear * p.force * FL * FV, (l, v, lp)


def _uncompiled(monkeypatch):
    monkeypatch.setattr(jit, "_COMPILED", False)


def test_tension_range_equals_the_formulas_compiled_and_not(monkeypatch):
    p = _params()
    ell, ell_dot = _states(p)
    passive, gain, (l, v, lp) = _reference(p, ell, ell_dot)
    # every piece of every curve is reached
    y = p.fvmax - 1
    for piece in (l < p.lmin, (p.lmin <= l) & (l < 1), (1 < l) & (l <= p.lmax), l > p.lmax, v <= -1,
                  (-1 < v) & (v <= 0), (0 < v) & (v <= y), v > y, lp <= 1, lp > 0.5 * (1 + p.bias_lmax)):
        assert piece.any()
    jit.prepare(policy="wait")
    fast = mu.force_range(p, ell, ell_dot)
    with monkeypatch.context() as mp:
        _uncompiled(mp)
        slow = mu.force_range(p, ell, ell_dot)
    for a, b in zip(fast, slow):  # the same code, no fastmath: the same bits
        np.testing.assert_array_equal(a, b)
    scale = p.gear * np.maximum(p.force, p.bias_force)
    np.testing.assert_allclose(fast.passive, passive, rtol=1e-12, atol=1e-12 * scale.max())
    np.testing.assert_allclose(fast.gain, gain, rtol=1e-12, atol=1e-12 * scale.max())
    np.testing.assert_array_equal(fast.f_min, fast.passive + fast.gain * p.act_min)
    np.testing.assert_array_equal(fast.f_max, fast.passive + fast.gain * p.act_max)
    # one state at a time (the evaluator's call) gives the same bits as the batch
    for t in (0, 57, 199):
        one = mu.force_range(p, ell[t], ell_dot[t])
        np.testing.assert_array_equal(one.f_max, fast.f_max[t])
        assert one.f_max.shape == (p.size,)


def test_curves_equal_the_formulas_compiled_and_not(monkeypatch):
    p = _params()
    ell, ell_dot = _states(p)
    _, _, (l, v, lp) = _reference(p, ell, ell_dot)
    jit.prepare(policy="wait")
    fast = [mu.fl(p, l), mu.fv(p, v), mu.fp(p, lp)]
    with monkeypatch.context() as mp:
        _uncompiled(mp)
        slow = [mu.fl(p, l), mu.fv(p, v), mu.fp(p, lp)]
    for a, b in zip(fast, slow):
        np.testing.assert_array_equal(a, b)
    passive, gain, _ = _reference(p, ell, ell_dot)
    np.testing.assert_allclose(p.gear * p.force * fast[0] * fast[1], gain, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(p.gear * p.bias_force * fast[2], passive, rtol=1e-12, atol=1e-9)
    # a curve broadcasts a scalar to every muscle
    assert mu.fl(p, 1.0).shape == (p.size,) and np.all(mu.fl(p, 1.0) == 1.0)


def _ruiz_reference(A, sweeps=10):
    r, d = np.ones(A.shape[0]), np.ones(A.shape[1])
    B = np.abs(A)
    for _ in range(sweeps):
        S = r[:, None] * B * d[None, :]
        row, col = S.max(axis=1), S.max(axis=0)
        r /= np.sqrt(np.where(row == 0, 1.0, row))
        d /= np.sqrt(np.where(col == 0, 1.0, col))
    return np.exp2(np.round(np.log2(r))), np.exp2(np.round(np.log2(d)))


@pytest.mark.parametrize("seed", range(5))
def test_ruiz_equals_the_sweeps_compiled_and_not(monkeypatch, seed):
    from mcdm_pin.scaling import equilibrate

    rng = np.random.default_rng(seed)
    A = rng.normal(size=(27, 85)) * 10.0 ** rng.uniform(-7, 3, (1, 85)) * 10.0 ** rng.uniform(-2, 2, (27, 1))
    if seed >= 3:  # mostly zeros, as a muscle arm's equations (the sweeps walk the nonzeros alone)
        A[rng.random(A.shape) < 0.88] = 0.0
    A[:, 5] = 0.0  # a column the equations do not see
    A[3] = 0.0  # and an empty row
    jit.prepare(policy="wait")
    fast = equilibrate(A)
    with monkeypatch.context() as mp:
        _uncompiled(mp)
        slow = equilibrate(A)
    ref = _ruiz_reference(A)
    for a, b, c in zip(fast, slow, ref):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a, c)
    r, d = fast
    assert r[3] == 1.0 and d[5] == 1.0
    S = np.abs(r[:, None] * A * d[None, :])
    live = S.max(axis=1) > 0
    assert np.all(S.max(axis=1)[live] <= 4.0) and np.all(S.max(axis=1)[live] >= 0.25)


def test_coupling_basis_compiled_and_not_and_by_differences(monkeypatch, tmp_path):
    """MyoSuite's arm: 11 couplings of the shoulder rhythm (dependents on the elevation angle)."""
    from mcdm_pin import Robot, load_trajectory

    from .conftest import REPO

    monkeypatch.chdir(tmp_path)
    robot = Robot.load(REPO / "robots" / "myosuite" / "myoarm.yaml")
    cs = robot.couplings
    traj = load_trajectory(robot, "abduction")
    jit.prepare(policy="wait")
    for k in (0, 37, 100):
        q = traj.q[k]
        fast = cs.basis(q)
        with monkeypatch.context() as mp:
            _uncompiled(mp)
            slow = cs.basis(q)
        np.testing.assert_array_equal(fast, slow)
        assert fast.shape == (robot.nv, cs.n) and np.count_nonzero(fast) > cs.n
        # dq/dz by central differences of fill() along each independent coordinate
        import pinocchio as pin

        h = 1e-6
        for a, i in enumerate(cs.independent):
            dv = np.zeros(robot.nv)
            dv[i] = h
            up = cs.fill(pin.integrate(robot.model, q, dv))[0]
            down = cs.fill(pin.integrate(robot.model, q, -dv))[0]
            np.testing.assert_allclose(pin.difference(robot.model, down, up) / (2 * h), fast[:, a], atol=1e-7)


def test_the_kernels_are_registered_and_stamp_the_cache():
    names = jit.entry_points()
    assert {"mcdm_pin.model.muscle_kernels.tension_range", "mcdm_pin.model.muscle_kernels.curves",
            "mcdm_pin.model.kernels.ruiz", "mcdm_pin.model.kernels.scale_factors",
            "mcdm_pin.model.coupling_kernels.coupling_basis"} <= set(names)
    assert "muscle_kernels.py" in {p.name for p in jit.kernel_sources()}


def test_activations_in_the_answer_check_equal_the_formula():
    """The answer check's compiled activations (``_fast.activations``, beside the outputs) equal
    ``_activations`` (numpy, :func:`mcdm_pin.model.muscles.activation`) bit for bit: every cable a
    muscle or some, gains of zero at and away from the passive force, NaN on the other cables."""
    from types import SimpleNamespace

    from mcdm_pin.inverse_dynamics import _activations, _tensions
    from mcdm_pin.solvers import _fast

    jit.prepare(policy="wait")
    rng = np.random.default_rng(7)
    m, bound = 12, 1e-6
    for index in (np.arange(m), np.array([1, 4, 5, 9, 11])):
        k = len(index)
        passive, gain = rng.uniform(0, 50, k), rng.uniform(10, 900, k)
        gain[[0, 2]] = 0.0
        f = rng.uniform(0, 900, m + 3)  # (three actuators' torques after the cables)
        f[index[0]] = passive[0] + 0.5 * bound  # at the passive force: a_min; index[2]: away, NaN
        state = mu.MuscleState(passive, gain, passive, passive + gain, np.broadcast_to(0.01, (k,)), np.ones(k))
        terms = SimpleNamespace(muscles=state)
        cables = SimpleNamespace(muscle_index=index, all_muscles=len(index) == m, m=m)
        compiled = _fast.activations(_tensions(terms, cables, bound), f, m)
        reference = _activations(terms, f[:m], cables, bound)
        np.testing.assert_array_equal(compiled, reference)
        assert compiled[index[0]] == 0.01 and np.isnan(compiled[index[2]])
        assert np.isnan(compiled[np.setdiff1d(np.arange(m), index)]).all()
    none = _tensions(SimpleNamespace(muscles=None), None, bound)
    assert _fast.activations(none, np.ones(3), 3).shape == (0,)


def _padded_reference(act, qp, eom, nv, terms, cone_frames):
    """The actuated problem's arrays as numpy pads them (``[f; tau_act]``: ``-S`` beside the equation
    of motion, zero blocks, the actuators' bounds and weights)."""
    m, k = qp.n, act.n
    n = m + k
    A = np.zeros((qp.A.shape[0], n))
    A[:, :m] = qp.A
    if eom:
        A[:nv, m:] = -act.rows(terms)
    G0 = qp.cone_arrays()[0]
    G = np.zeros((len(G0), 3, n))
    G[:, :, :m] = G0
    RT_act = getattr(terms, "RT_act", None)
    if RT_act is not None:
        for i, c in enumerate(qp.cones):
            G[i, :, m:] = act._cone_block(c, terms, RT_act, cone_frames)
    out = dict(A=A, G=G, c=np.concatenate([qp.c, np.zeros(k)]), lb=np.concatenate([qp.lb, act.lo]),
               ub=np.concatenate([qp.ub, act.hi]))
    if qp._P is not None or not qp.structured:
        P = np.zeros((n, n))
        P[:m, :m] = qp.P
        P.flat[m * (n + 1):: n + 1] = act.weight
        out["P"] = P
    if qp.structured:
        out["P_diag"] = np.concatenate([qp.P_diag, act.weight])
        F = np.zeros((qp.P_factor.shape[0], n))
        F[:, :m] = qp.P_factor
        out["P_factor"] = F
    if qp.norm_weight is not None:
        out["norm_weight"] = np.concatenate([qp.norm_weight, np.ones(k)])
    return out


def _hybrid(name):
    """``(robot, trajectory, problem)`` of a robot with actuators beside its muscles."""
    from mcdm_pin import Robot, load_trajectory
    from mcdm_pin.problem import case_problem

    from .conftest import REPO

    if name.startswith("myoarm"):
        arm = Robot.load(REPO / "robots" / "myosuite" / "myoarm.yaml")
        return arm, load_trajectory(arm, "abduction"), case_problem(arm, int(name[-1]))
    from mcdm_pin.osim.motion import read_table
    from mcdm_pin.osim.rmr import RATE, frame_rows, frame_states, rmr_problem, rmr_robot
    from mcdm_pin.trajectory import Trajectory

    shoulder = rmr_robot("abd01")
    files = tuple(REPO / "robots" / "opensim" / "motions" / "abd01" / f"Kinematics_{k}.sto" for k in ("q", "u", "dudt"))
    rows = frame_rows(files)
    rows = rows[np.isin(np.round(rows / RATE, 9), np.round(read_table(files[0]).time, 9))][:3]
    q, v, a = frame_states(shoulder, files, rows)
    return shoulder, Trajectory(name="abd01", t=rows / RATE, q=q, qd=v, qdd=a), rmr_problem(shoulder, True)


@pytest.mark.parametrize("name", ["myoarm case 1", "myoarm case 3", "rmr"])
def test_the_actuated_problem_is_padded_to_the_bit_compiled_and_not(monkeypatch, tmp_path, name):
    """:meth:`mcdm_pin.problem._Actuation.extend` (one compiled pass,
    :func:`mcdm_pin.model.actuated_kernels.actuated_arrays`) gives numpy's padding bit for bit (signs
    of zero included), compiled and not: MyoSuite's arm with the activations' objective (case 1)
    and with the interaction objective and its cone (case 3), RMR's shoulder
    (its problem with the glenohumeral cone) with its closed loop's share of the actuator torques in
    the cone (``RT_act``)."""
    from mcdm_pin import InverseDynamics
    from mcdm_pin.problem import Context

    monkeypatch.chdir(tmp_path)
    robot, traj, problem = _hybrid(name)
    ident = InverseDynamics(robot, problem)
    problem, act = ident.problem, ident.problem.actuation
    assert act is not None
    jit.prepare(policy="wait")
    for k in (0, len(traj) // 2):
        q, qd, qdd = traj.q[k], traj.qd[k], traj.qdd[k]
        terms = ident.evaluate(robot.check_configuration(q), qd, qdd, checked=True)
        monkeypatch.setattr(problem, "actuation", None)
        qp = problem.assemble(terms, Context(robot, None))
        monkeypatch.setattr(problem, "actuation", act)
        plan = problem._plan
        args = (qp, plan["eom"], terms.L.shape[1], terms, plan["cone_frames"])
        fast = act.extend(*args)
        with monkeypatch.context() as mp:
            _uncompiled(mp)
            slow = act.extend(*args)
        ref = _padded_reference(act, *args)
        assert (getattr(terms, "RT_act", None) is not None) == (name == "rmr")
        for out in (fast, slow):
            got = dict(A=out.A, G=out.cone_arrays()[0], c=out.c, lb=out.lb, ub=out.ub)
            if "P" in ref:
                got["P"] = out._P
            if qp.structured:
                got["P_diag"], got["P_factor"] = out.P_diag, out.P_factor
            if qp.norm_weight is not None:
                got["norm_weight"] = out.norm_weight
            assert set(got) == set(ref) and (out._P is None) == ("P" not in ref)
            for key, want in ref.items():
                np.testing.assert_array_equal(got[key], want, err_msg=key)
                np.testing.assert_array_equal(np.signbit(got[key]), np.signbit(want), err_msg=key)
            for i, cone in enumerate(out.cones):
                np.testing.assert_array_equal(cone.G, ref["G"][i])
            assert out.b is qp.b and out.r == qp.r
