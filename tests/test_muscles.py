"""MuJoCo's muscle as a cable's force range (mcdm_pin.model.muscles) against MuJoCo 4.0 itself.

References: ``data.actuator_force`` after ``mj_fwdPosition``/``mj_fwdVelocity``/``mj_fwdActuation`` on
MyoSuite's models (Apache-2.0; the arm after MoBL, Holzbaur 2005), MuJoCo's own ``mju_muscleGain`` and
``mju_muscleBias``, and a plain scalar transcription of the curves' formulas (the module's docstring).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco", reason="MuJoCo is the reference of these tests")

from mcdm_pin.exceptions import ModelError, StateError  # noqa: E402
from mcdm_pin.model import muscles as mu  # noqa: E402

MYO_MODELS = ("myoelbow", "myoelbow_2dof", "myoarm_r")
N_STATES = 60
REL = 1e-9


@pytest.fixture(scope="module")
def myo(tmp_path_factory):
    """The three MyoSuite models, compiled once in a temporary folder (MuJoCo may write a log)."""
    myo_sim = pytest.importorskip("myo_sim", reason="MyoSuite's models (myosuite / myo_sim) are not installed")
    models = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(tmp_path_factory.mktemp("myo"))
        for name in MYO_MODELS[:2]:
            models[name] = mujoco.MjModel.from_xml_path(str(myo_sim.get_xml_path(name)))
        with pytest.warns(UserWarning, match="empty prefix"):
            xml = myo_sim.load_spec("myoarm_r").to_xml()
        models["myoarm_r"] = mujoco.MjModel.from_xml_string(xml)
    return models


def _random_state(m, d, rng, k):
    """qpos of hinges/slides uniform in their ranges, qvel normal at three scales (rad/s; the largest
    makes some muscles shorten faster than vmax), act uniform in [0, 1]; MuJoCo's forces at that state."""
    mujoco.mj_resetData(m, d)
    for j in range(m.njnt):
        if m.jnt_type[j] in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            lo, hi = m.jnt_range[j] if m.jnt_limited[j] else (-1.0, 1.0)
            d.qpos[m.jnt_qposadr[j]] = rng.uniform(lo, hi)
    d.qvel[:] = rng.normal(0.0, (0.3, 5.0, 100.0)[k % 3], m.nv)
    d.act[:] = rng.uniform(0.0, 1.0, m.na)
    mujoco.mj_fwdPosition(m, d)
    mujoco.mj_fwdVelocity(m, d)
    mujoco.mj_fwdActuation(m, d)


@pytest.mark.parametrize("name", MYO_MODELS)
def test_tension_matches_mujoco_actuator_force(myo, name, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    m = myo[name]
    found = mu.from_mujoco(m)
    p, ten, ids = found.params, found.tendon_ids, found.actuator_ids
    assert p.size == m.nu == len(ten) and found.skipped == ()
    assert (name != "myoarm_r") or p.size == 63
    d = mujoco.MjData(m)
    rng = np.random.default_rng(20261125)
    worst, ls, vs, lps = 0.0, [], [], []
    for k in range(N_STATES):
        _random_state(m, d, rng, k)
        ell, ell_dot = d.ten_length[ten], d.ten_velocity[ten]
        np.testing.assert_allclose(d.actuator_length[ids], p.gear * ell, rtol=1e-14, atol=0)
        np.testing.assert_allclose(d.actuator_velocity[ids], p.gear * ell_dot, rtol=1e-14, atol=1e-300)
        st = mu.force_range(p, ell, ell_dot)
        a = d.act[m.actuator_actadr[ids]]
        ours = st.passive + st.gain * a
        ref = -p.gear * d.actuator_force[ids]          # tension = -gear * actuator force (>= 0)
        assert np.all(ref >= 0)
        worst = max(worst, np.max(np.abs(ours - ref) / np.maximum(np.abs(ref), 1e-12 * p.force)))
        assert np.all(st.f_min <= ours + 1e-9) and np.all(ours <= st.f_max + 1e-9 * (1 + st.f_max))
        live = st.gain > 1e-9 * p.force
        np.testing.assert_allclose(mu.activation(st, ref)[live], a[live], rtol=1e-9, atol=1e-9)
        l, v = mu.normalised(p, ell, ell_dot)
        ls.append(l), vs.append(v), lps.append(mu.normalised_passive(p, ell))
    assert worst <= REL, f"{name}: max relative error {worst:.3g}"
    # the states reach every piece of F_V and F_P, and the rising and falling halves of F_L
    l, v, lp = np.array(ls), np.array(vs), np.array(lps)
    y = p.fvmax - 1
    for piece in (v <= -1, (-1 < v) & (v <= 0), (0 < v) & (v <= y), v > y, lp <= 1,
                  (1 < lp) & (lp <= 0.5 * (1 + p.bias_lmax)), l < 1, l > 1):
        assert piece.any()


def test_myosuite_activation_bounds(myo):
    """What MyoSuite declares: ctrlrange [0.001, 1] (elbow) or [0, 1] (arm), no actrange, F0 given."""
    for name, lo in (("myoelbow", 0.001), ("myoelbow_2dof", 0.001), ("myoarm_r", 0.0)):
        p = mu.from_mujoco(myo[name]).params
        np.testing.assert_array_equal(p.act_min, lo)
        np.testing.assert_array_equal(p.act_max, 1.0)
        assert np.all(np.isinf(p.actrange)) and np.all(p.force > 0)
    # myoarm_r's SUPSP has biasprm != gainprm: its passive side has its own range and F0
    p = mu.from_mujoco(myo["myoarm_r"]).params
    k = p.names.index("SUPSP")
    assert p.bias_force[k] != p.force[k] and np.any(p.bias_range[k] != p.range[k])


# ------------------------------------------------------------------------------ curves


def _params(**kw):
    """Three hand-made muscles (gear 1, range = lengthrange so that l equals the tendon length)."""
    base = dict(range=[[0.5, 1.6], [0.75, 1.05], [0.9, 1.3]], force=[300.0, 120.0, 50.0], scale=[200.0] * 3,
                lmin=[0.5, 0.3, 0.42], lmax=[1.6, 1.9, 2.1], vmax=[1.5, 10.0, 15.0], fpmax=[1.3, 0.5, 1.87],
                fvmax=[1.2, 1.4, 1.9], gear=[1.0] * 3)
    base.update(kw)
    base.setdefault("bias_range", base["range"])
    base.setdefault("bias_force", base["force"])
    base.setdefault("bias_lmax", base["lmax"])
    base.setdefault("lengthrange", base["range"])
    inf = [[-np.inf, np.inf]] * 3
    return mu.MuscleParams(names=("a", "b", "c"), ctrlrange=inf, actrange=inf, act_min=[0.0] * 3,
                           act_max=[1.0] * 3, **base)


def _fl(l, lmin, lmax):
    if l < lmin or l > lmax:
        return 0.0
    a, b = (lmin + 1) / 2, (1 + lmax) / 2
    if l <= a:
        return 0.5 * ((l - lmin) / (a - lmin)) ** 2
    if l <= 1:
        return 1 - 0.5 * ((1 - l) / (1 - a)) ** 2
    if l <= b:
        return 1 - 0.5 * ((l - 1) / (b - 1)) ** 2
    return 0.5 * ((lmax - l) / (lmax - b)) ** 2


def _fv(v, fvmax):
    if v <= -1:
        return 0.0
    if v <= 0:
        return (v + 1) ** 2
    y = fvmax - 1
    return fvmax - (y - v) ** 2 / y if v <= y else fvmax


def _fp(l, lmax, fpmax):
    b = (1 + lmax) / 2
    if l <= 1:
        return 0.0
    return fpmax * (0.5 * ((l - 1) / (b - 1)) ** 2 if l <= b else 0.5 + (l - b) / (b - 1))


def _edges(p, i):
    lmin, lmax, r = p.lmin[i], p.lmax[i], p.range[i]
    ls = [r[0], r[1], lmin, lmax, (lmin + 1) / 2, 1.0, (1 + lmax) / 2, lmin - 0.1, lmax + 0.1, 3 * lmax]
    vs = [-2.0, -1.0, -0.5, 0.0, 0.5 * (p.fvmax[i] - 1), p.fvmax[i] - 1, 1.0, 2.0]
    return ls, vs


def test_curves_at_edges_match_formulas_and_mujoco():
    p = _params()
    for i in range(p.size):
        ls, vs = _edges(p, i)
        col = np.zeros((len(ls), p.size))
        col[:, i] = ls
        got_fl, got_fp = mu.fl(p, col)[:, i], mu.fp(p, col)[:, i]
        prm = np.array([*p.range[i], p.force[i], p.scale[i], p.lmin[i], p.lmax[i], p.vmax[i], p.fpmax[i],
                        p.fvmax[i]])
        for l, a, b in zip(ls, got_fl, got_fp):
            assert a == pytest.approx(_fl(l, p.lmin[i], p.lmax[i]), rel=1e-14, abs=1e-15)
            assert b == pytest.approx(_fp(l, p.lmax[i], p.fpmax[i]), rel=1e-14, abs=1e-15)
            # mju_muscleBias takes the actuator length: here lengthrange == range, so L == l
            assert -mujoco.mju_muscleBias(l, p.lengthrange[i], 1.0, prm) == pytest.approx(p.force[i] * b, rel=1e-14,
                                                                                          abs=1e-12)
        col = np.zeros((len(vs), p.size))
        col[:, i] = vs
        got_fv = mu.fv(p, col)[:, i]
        L0 = p.optimal_length[i]
        for v, a in zip(vs, got_fv):
            assert a == pytest.approx(_fv(v, p.fvmax[i]), rel=1e-14, abs=1e-15)
            for l in ls:
                ref = -mujoco.mju_muscleGain(l, v * L0 * p.vmax[i], p.lengthrange[i], 1.0, prm)
                assert ref == pytest.approx(p.force[i] * _fl(l, p.lmin[i], p.lmax[i]) * a, rel=1e-13, abs=1e-12)


def test_curves_are_continuously_differentiable_across_pieces():
    p = _params()
    h = 1e-7
    for i in range(p.size):
        lmin, lmax, fvmax = p.lmin[i], p.lmax[i], p.fvmax[i]
        cases = [(mu.fl, [lmin, (lmin + 1) / 2, 1.0, (1 + lmax) / 2, lmax]),
                 (mu.fp, [1.0, (1 + lmax) / 2]), (mu.fv, [-1.0, 0.0, fvmax - 1])]
        for curve, points in cases:
            for x in points:
                col = np.zeros((5, p.size))
                col[:, i] = [x - 2 * h, x - h, x, x + h, x + 2 * h]
                y = curve(p, col)[:, i]
                assert abs(y[3] - y[1]) < 1e-5, (curve.__name__, i, x)
                left, right = (y[2] - y[0]) / (2 * h), (y[4] - y[2]) / (2 * h)   # one-sided slopes
                assert abs(left - right) < 1e-4 * (1 + abs(left)), (curve.__name__, i, x, left, right)


def test_length_slopes_match_central_differences():
    p = _params(gear=[1.0, 2.0, 0.5], lengthrange=[[0.3, 0.5], [0.2, 0.9], [0.05, 0.08]],
                bias_range=[[0.6, 1.5], [0.75, 1.05], [0.8, 1.4]], bias_lmax=[1.7, 1.9, 2.0])
    rng = np.random.default_rng(5)
    ell = p.length_at(rng.uniform(0.2, 2.4, (200, 3)))
    vel = rng.normal(0, 0.1, (200, 3))
    d_passive, d_gain = mu.length_slopes(p, ell, vel)
    h = 1e-7
    up, down = mu.force_range(p, ell + h, vel), mu.force_range(p, ell - h, vel)
    scale = p.gear * p.force / p.optimal_length * p.gear
    np.testing.assert_allclose(d_passive, (up.passive - down.passive) / (2 * h), rtol=0, atol=1e-5 * scale.max())
    np.testing.assert_allclose(d_gain, (up.gain - down.gain) / (2 * h), rtol=0, atol=1e-5 * scale.max())
    assert np.count_nonzero(d_passive) > 100 and np.count_nonzero(d_gain) > 100


def test_force_range_collapses_to_passive_where_gain_vanishes():
    p = _params()
    # tendon lengths beyond lmax (F_L = 0) and shortening faster than vmax (F_V = 0)
    ell = np.array([[2.0, 2.0, 2.5], [1.0, 1.0, 1.0]])
    vel = np.array([[0.0, 0.0, 0.0], [-1.01 * p.vmax[0] * p.optimal_length[0], -1e3, -1e3]])
    st = mu.force_range(p, ell, vel)
    np.testing.assert_array_equal(st.gain, 0.0)
    np.testing.assert_array_equal(st.f_min, st.passive)
    np.testing.assert_array_equal(st.f_max, st.passive)
    assert np.all(st.passive[0] > 0) and np.all(st.passive[1] == 0)
    a = mu.activation(st, st.passive)
    np.testing.assert_array_equal(a, st.a_min)
    assert np.all(np.isnan(mu.activation(st, st.passive + 1.0)))


def test_force_range_vectorised_over_instants_and_inverse():
    p = _params(gear=[1.0, 2.0, 0.5], lengthrange=[[0.3, 0.5], [0.2, 0.9], [0.05, 0.08]])
    rng = np.random.default_rng(3)
    ell = p.length_at(rng.uniform(0.4, 1.9, (7, 3)))
    vel = rng.normal(0, 0.2, (7, 3))
    st = mu.force_range(p, ell, vel)
    assert st.passive.shape == (7, 3)
    for t in range(7):
        row = mu.force_range(p, ell[t], vel[t])
        np.testing.assert_array_equal(row.f_max, st.f_max[t])
    l, _ = mu.normalised(p, ell, vel)
    np.testing.assert_allclose(p.length_at(l), ell, rtol=1e-14)
    a = rng.uniform(0, 1, (7, 3))
    live = st.gain > 0
    np.testing.assert_allclose(mu.activation(st, st.passive + st.gain * a)[live], a[live], rtol=1e-12)
    with pytest.raises(StateError, match="last axis of size 3"):
        mu.force_range(p, ell[:, :2], vel[:, :2])
    with pytest.raises(StateError, match="tendon_velocities must be finite"):
        mu.force_range(p, ell, np.where(vel > 0, np.nan, vel))


# ------------------------------------------------------------------------------ MJCF

ARM = """
<mujoco>
  <worldbody>
    <site name="anchor" pos="0 0 0.3"/>
    <body name="arm">
      <joint name="hinge" type="hinge" axis="0 1 0" range="-90 90" limited="true"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.02" mass="1.5"/>
      <site name="insert" pos="0.2 0 0"/>
    </body>
  </worldbody>
  <tendon><spatial name="t1"><site site="anchor"/><site site="insert"/></spatial></tendon>
  <actuator>
    <muscle name="scaled" tendon="t1" force="-1" scale="350" range="0.7 1.2"/>
    <muscle name="geared" tendon="t1" force="120" gear="2" ctrllimited="true" ctrlrange="0.05 0.9"/>
    {extra}
  </actuator>
</mujoco>"""


def test_force_from_scale_and_acc0(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    m = mujoco.MjModel.from_xml_string(ARM.format(extra='<motor name="drive" joint="hinge"/>'))
    found = mu.from_mujoco(m)
    p = found.params
    assert p.names == ("scaled", "geared") and found.skipped[0][0] == "drive"
    assert m.actuator_gainprm[0, 2] == -1          # MuJoCo 4.0 keeps force=-1 and divides at run time
    assert p.force[0] == pytest.approx(350 / m.actuator_acc0[0], rel=1e-15) and p.force[1] == 120
    assert (p.act_min[1], p.act_max[1]) == (0.05, 0.9)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(1)
    for k in range(20):
        _random_state(m, d, rng, k)
        st = mu.force_range(p, d.ten_length[found.tendon_ids], d.ten_velocity[found.tendon_ids])
        ref = -p.gear * d.actuator_force[:2]
        np.testing.assert_allclose(st.passive + st.gain * d.act[:2], ref, rtol=REL, atol=1e-12)


@pytest.mark.parametrize("extra, why", [
    ('<muscle name="on_joint" joint="hinge"/>', "on_joint.*mjTRN_JOINT"),
    ('<muscle name="limited" tendon="t1" forcelimited="true" forcerange="-100 0"/>', "limited.*forcelimited"),
    ('<general name="mixed" tendon="t1" dyntype="none" gaintype="muscle" biastype="muscle" '
     'gainprm="0.75 1.05 100 200 0.5 1.6 1.5 1.3 1.2" biasprm="0.75 1.05 100 200 0.5 1.6 1.5 1.3 1.2"/>',
     "mixed.*mjDYN_NONE"),
])
def test_refuses_muscles_that_are_not_cables(monkeypatch, tmp_path, extra, why):
    monkeypatch.chdir(tmp_path)
    m = mujoco.MjModel.from_xml_string(ARM.format(extra=extra))
    with pytest.raises(ModelError, match=why):
        mu.from_mujoco(m)


# a hinge between two muscles on their own tendons, and an ``{extra}`` actuator
ELBOW = """
<mujoco>
  <worldbody>
    <site name="up" pos="0 0 0.3"/>
    <site name="down" pos="0 0 -0.3"/>
    <body name="arm">
      <joint name="hinge" type="hinge" axis="0 1 0" range="-60 60" limited="true"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.02" mass="1.5"/>
      <site name="top" pos="0.2 0 0.02"/>
      <site name="bottom" pos="0.2 0 -0.02"/>
    </body>
  </worldbody>
  <tendon>
    <spatial name="flexor"><site site="up"/><site site="top"/></spatial>
    <spatial name="extensor"><site site="down"/><site site="bottom"/></spatial>
  </tendon>
  <actuator>
    <muscle name="flexor" tendon="flexor" force="200"/>
    <muscle name="extensor" tendon="extensor" force="200"/>
    {extra}
  </actuator>
</mujoco>"""


@pytest.mark.parametrize("extra, bounds", [
    ('<motor name="exo" joint="hinge" gear="2"/>', (-math.inf, math.inf)),  # no control range: unbounded
    ('<motor name="exo" joint="hinge" gear="2" forcelimited="true" forcerange="-3 5"/>', (-6.0, 10.0)),
    ('<motor name="exo" joint="hinge" gear="2" ctrllimited="true" ctrlrange="-1 0.5"/>', (-2.0, 1.0)),
])
def test_joint_motors_with_and_without_a_control_range(monkeypatch, tmp_path, extra, bounds):
    """A plain motor on a hinge is an actuator of its joint, bounded by ``gear x`` its control range and
    force range; without either it is unbounded, and its weight in the objective keeps its torque
    finite (an exoskeleton's motor: MyoSuite's ``myoelbow_exo``). Every back-end gives one answer."""
    from mcdm_pin import InverseDynamics
    from mcdm_pin.robot import Robot

    monkeypatch.chdir(tmp_path)
    robot = Robot.from_mujoco(mujoco.MjModel.from_xml_string(ELBOW.format(extra=extra)), "elbow", "elbow")
    (act,) = robot.actuators
    assert (act.label, act.weight) == ("exo", 1.0)
    assert (float(act.tau_min[0]), float(act.tau_max[0])) == bounds
    q, qd, qdd = np.array([0.3]), np.array([0.5]), np.array([4.0])
    ours = InverseDynamics.for_case(robot, 1).solve(q, qd, qdd)
    ref = InverseDynamics.for_case(robot, 1, solver="clarabel").solve(q, qd, qdd)
    assert ours.status == ref.status == "optimal" and np.all(np.isfinite(ours.tau_act))
    assert ours.objective == pytest.approx(ref.objective, rel=1e-9, abs=1e-12)
    np.testing.assert_allclose(np.concatenate([ours.f, ours.tau_act]), np.concatenate([ref.f, ref.tau_act]),
                               rtol=1e-7, atol=1e-9)


def test_an_mjcf_sidecar_weighs_the_joint_motors(tmp_path):
    """``actuator_weights`` in an ``mjcf:`` sidecar sets a joint motor's ``w`` of ``w |tau|^2``: a cheaper
    exoskeleton's motor takes more of the load and the muscles less. A name that is not a joint motor,
    a weight below 0 or a list is refused, naming the field."""
    from mcdm_pin import InverseDynamics, Robot
    from mcdm_pin.exceptions import SidecarError

    (tmp_path / "elbow.xml").write_text(ELBOW.format(extra='<motor name="exo" joint="hinge" gear="2"/>'))
    side = tmp_path / "elbow.yaml"
    state = np.array([0.3]), np.array([0.0]), np.array([20.0])
    torque, activation = [], []
    for w in (1.0, 1e-4):
        side.write_text(f"version: 1\nmjcf: elbow.xml\nactuator_weights: {{exo: {w}}}\n")
        robot = Robot.load(side)
        assert robot.actuators[0].weight == w
        res = InverseDynamics.for_case(robot, 1).solve(*state)
        assert res.status == "optimal"
        torque.append(abs(float(res.tau_act[0])))
        activation.append(float(np.max(res.activation)))
    assert torque[1] > 100 * torque[0] and activation[1] < activation[0]
    for raw, why in [("{exoo: 1}", r"actuator_weights names \['exoo'\].*those: 'exo'"),
                     ("{exo: -1}", r"actuator_weights\.exo: expected a number >= 0"),
                     ("[1]", "actuator_weights: expected a mapping")]:
        side.write_text(f"version: 1\nmjcf: elbow.xml\nactuator_weights: {raw}\n")
        with pytest.raises(SidecarError, match=why):
            Robot.load(side)


@pytest.mark.parametrize("extra, why", [
    ('<motor name="push" tendon="flexor"/>', "'push'.*not within \\[0, inf\\)"),  # it could push
    ('<general name="dead" joint="hinge" gainprm="0"/>', "'dead'.*no gain"),
])
def test_refuses_motors_that_are_not_cables_or_actuators(monkeypatch, tmp_path, extra, why):
    from mcdm_pin.robot import Robot

    monkeypatch.chdir(tmp_path)
    with pytest.raises(ModelError, match=why):
        Robot.from_mujoco(mujoco.MjModel.from_xml_string(ELBOW.format(extra=extra)), "elbow", "elbow")


def test_params_validate():
    with pytest.raises(ModelError, match="gear.*'b'"):
        _params(gear=[1.0, -1.0, 1.0])
    with pytest.raises(ModelError, match="lmin: expected shape"):
        _params(lmin=[0.5, 0.5])
    assert math.isclose(_params().optimal_length[0], 1.0)
