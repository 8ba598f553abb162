"""mcdm_pin.mjcf.model against MuJoCo: kinematics, inertias, mass matrix, inverse dynamics, joint
wrenches and passive forces on small MJCF models and on MyoSuite's; and the vendored MyoSuite files
(robots/myosuite/) against the models they were written from.

MuJoCo runs in a temporary working folder (it writes MUJOCO_LOG.TXT there on warnings).
"""

from __future__ import annotations

import contextlib
import sys
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin.exceptions import ModelError, StateError
from mcdm_pin.mjcf.model import BALL, FREE, HINGE, SLIDE, build_model

mujoco = pytest.importorskip("mujoco")

REPO = Path(__file__).resolve().parents[1]
VENDORED = REPO / "robots" / "myosuite"
N_STATES = 50

# Every joint kind, anchors off the body origin, non-unit axes, several joints on one body,
# a welded body, ref on a hinge and a slide, armature, damping, stiffness with springref, and
# bodies, geoms and sites oriented by quat and euler.
SMALL = """<mujoco><option gravity="0.3 -1 -9.81"/>
<worldbody>
 <geom name="floor" type="plane" size="1 1 .1" pos="0 0 -1"/>
 <body name="base" pos="0.1 0.2 0.3" euler="10 20 30">
  <geom type="box" size=".1 .2 .3" mass="2" pos="0.01 0.02 0" euler="5 0 3"/>
  <body name="b1" pos="0 0 0.5" quat="0.9 0.1 0.2 0.3">
   <joint name="h1" type="hinge" pos="0.05 -0.02 0.1" axis="1 2 3" ref="17" range="-40 60"
          damping="0.7" stiffness="2" springref="5" armature="0.02"/>
   <geom name="arm" type="capsule" fromto="0 0 0 0 0 .4" size=".05" mass="1.3"/>
   <site name="s1" pos=".1 .2 .3" euler="30 40 50"/>
   <body name="b2" pos="0 0.1 0.4">
    <joint name="j_a" type="hinge" pos="0.02 0 0" axis="0 1 0" damping="0.1"/>
    <joint name="j_b" type="hinge" pos="0 0.03 0.01" axis="1 1 0" stiffness="0.4"/>
    <joint name="j_c" type="slide" pos="0.5 0 0" axis="0 0.3 1" ref="-0.1" armature="0.1"
           stiffness="3" springref="0.2"/>
    <geom type="ellipsoid" size=".1 .05 .2" pos="0.1 0 0.1" quat="1 0.2 0 0.1"/>
    <body name="welded" pos="0.2 0 0" euler="0 90 0">
     <geom type="box" size=".05 .06 .07" mass="0.4" euler="0 0 20"/>
     <site pos="0.01 0 0" quat="0 1 1 0"/>
     <body name="b3" pos="0.1 0 0">
      <joint name="ball" type="ball" pos="0.01 0.02 0.03" damping="0.3" armature="0.01"/>
      <geom type="cylinder" size=".03 .1" mass="0.5" pos="0 0 0.1"/>
      <body name="b4" pos="0 0 0.2"><joint name="sl" type="slide" axis="0 0 1" damping="2"/>
       <geom type="sphere" size=".03" mass="0.2"/></body>
     </body>
    </body>
   </body>
  </body>
 </body>
 <body name="floater" pos="1 2 3" quat="0 1 0 0"><joint name="fj" type="free" damping="0.4"/>
  <geom type="box" size=".1 .2 .3" mass="3" pos="0.1 0 0" euler="10 0 0"/>
  <body name="fc" pos="0.3 0 0"><joint name="fh" axis="0 0 1" pos="0 0.1 0" damping="0.2"/>
   <geom type="sphere" size=".1" pos="0.1 0 0"/></body>
 </body>
</worldbody></mujoco>"""

_DSBL = mujoco.mjtDisableBit
NO_CONSTRAINTS = (_DSBL.mjDSBL_CONTACT | _DSBL.mjDSBL_CONSTRAINT | _DSBL.mjDSBL_EQUALITY
                  | _DSBL.mjDSBL_ACTUATION | _DSBL.mjDSBL_SPRING | _DSBL.mjDSBL_DAMPER)


@pytest.fixture(autouse=True)
def _tmp_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def _myo(name):
    myo_sim = pytest.importorskip("myo_sim")
    if name == "myoarm_r":
        with warnings.catch_warnings():  # myo_sim's own note on attaching with an empty prefix
            warnings.simplefilter("ignore", UserWarning)
            return mujoco.MjModel.from_xml_string(myo_sim.load_spec("myoarm_r").to_xml())
    return mujoco.MjModel.from_xml_path(str(myo_sim.get_xml_path(name)))


@pytest.fixture(scope="module")
def myoarm(tmp_path_factory):
    with contextlib.chdir(tmp_path_factory.mktemp("mujoco")):  # MUJOCO_LOG.TXT lands there
        return _myo("myoarm_r")


def random_state(mj, rng):
    """qpos within the joint ranges (angles in [-pi, pi] where unlimited, random unit quaternions),
    and normal qvel, qacc."""
    qpos = np.array(mj.qpos0)
    for j in range(mj.njnt):
        a, kind = mj.jnt_qposadr[j], mj.jnt_type[j]
        if kind in (HINGE, SLIDE):
            lo, hi = mj.jnt_range[j] if mj.jnt_limited[j] else (-np.pi, np.pi)
            qpos[a] = rng.uniform(lo, hi)
            continue
        if kind == FREE:
            qpos[a:a + 3] = rng.normal(size=3)
            a += 3
        quat = rng.normal(size=4)
        qpos[a:a + 4] = quat / np.linalg.norm(quat)
    return qpos, rng.normal(size=mj.nv), rng.normal(size=mj.nv)


def _placements(data, frames):
    return (np.array([data.oMf[int(f)].translation for f in frames]).reshape(-1, 3),
            np.array([data.oMf[int(f)].rotation for f in frames]).reshape(-1, 3, 3))


def _world_inertia(mj, d, b):
    """6x6 spatial inertia (Pinocchio's linear-angular order, world axes, about the world origin)
    of MuJoCo body b, from MuJoCo's own xipos, ximat."""
    rot = d.ximat[b].reshape(3, 3)
    inertia = pin.Inertia(mj.body_mass[b], np.zeros(3), rot @ np.diag(mj.body_inertia[b]) @ rot.T)
    return pin.SE3(np.eye(3), d.xipos[b].copy()).act(inertia).matrix()


def _relative(a, b):
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def compare(mj, built, n_states=N_STATES, seed=0):
    """Largest errors of the Pinocchio model against MuJoCo over random states."""
    data = built.model.createData()
    d, d_passive = mujoco.MjData(mj), mujoco.MjData(mj)  # apart: mj_forward leaves actuator forces
    rng = np.random.default_rng(seed)                      # that mj_rnePostConstraint would reuse
    err = dict.fromkeys(("pose", "inertia", "M", "rnea", "cfrc_int", "passive", "maps"), 0.0)
    flags = mj.opt.disableflags
    try:
        for _ in range(n_states):
            qpos, qvel, qacc = random_state(mj, rng)
            mj.opt.disableflags = NO_CONSTRAINTS
            d.qpos[:], d.qvel[:], d.qacc[:] = qpos, qvel, qacc
            mujoco.mj_inverse(mj, d)
            mujoco.mj_rnePostConstraint(mj, d)
            mj.opt.disableflags = flags
            d_passive.qpos[:], d_passive.qvel[:] = qpos, qvel
            mujoco.mj_forward(mj, d_passive)
            for key, value in _errors(mj, built, d, d_passive, data, qpos, qvel, qacc).items():
                err[key] = max(err[key], float(value))
    finally:
        mj.opt.disableflags = flags
    return err


def _errors(mj, built, d, d_passive, data, qpos, qvel, qacc):
    """Errors at one state: d after mj_inverse + mj_rnePostConstraint without constraints,
    actuation and passive forces; d_passive after mj_forward with the model's own flags."""
    model = built.model
    q, v, a = built.to_pin_q(qpos), built.to_pin_v(qvel, qpos), built.to_pin_a(qacc, qpos, qvel)
    err = {"maps": max(np.abs(built.to_mj_qpos(q) - qpos).max(), np.abs(built.to_mj_qvel(v, q) - qvel).max())}
    pin.forwardKinematics(model, data, q, v, a)
    pin.updateFramePlacements(model, data)
    err["pose"] = 0.0
    for frames, pos, mat in ((built.body_frame, d.xpos, d.xmat), (built.site_frame, d.site_xpos, d.site_xmat),
                             (built.geom_frame, d.geom_xpos, d.geom_xmat)):
        p, r = _placements(data, frames)
        err["pose"] = max(err["pose"], np.abs(p - pos).max(initial=0),
                          np.abs(r - mat.reshape(-1, 3, 3)).max(initial=0))
    err["inertia"] = _joint_inertia_error(mj, d, built, data)
    for b in range(1, mj.nbody):
        frame = model.frames[int(built.body_frame[b])]
        mine = data.oMf[int(built.body_frame[b])].act(frame.inertia).matrix()
        err["inertia"] = max(err["inertia"], _relative(mine, _world_inertia(mj, d, b)))
    rot = np.column_stack([built.to_pin_v(e, qpos) for e in np.eye(mj.nv)])  # v = rot @ qvel
    full = np.zeros((mj.nv, mj.nv))
    mujoco.mj_fullM(mj, d, full)
    mass = pin.crba(model, data, q)
    err["M"] = _relative(rot @ full @ rot.T, np.triu(mass) + np.triu(mass, 1).T)
    tau = pin.rnea(model, data, q, v, a)
    err["rnea"] = _relative(built.to_pin_v(d.qfrc_inverse, qpos), tau)
    err["cfrc_int"] = _cfrc_error(mj, d, built, data)
    passive = d_passive.qfrc_spring + d_passive.qfrc_damper
    err["passive"] = np.abs(built.to_pin_v(passive, qpos) - built.joint_passive(q, v)).max()
    return err


def _joint_inertia_error(mj, d, built, data):
    """model.inertias[j] (moved to the world) against the sum of its MuJoCo bodies' inertias."""
    worst = 0.0
    for j in range(1, built.model.njoints):
        bodies = np.flatnonzero(built.body_joint == j)
        total = sum(_world_inertia(mj, d, b) for b in bodies)
        worst = max(worst, _relative(data.oMi[j].act(built.model.inertias[j]).matrix(), total))
    return worst


def _cfrc_error(mj, d, built, data):
    """MuJoCo's cfrc_int (world axes, [torque, force], moment about the subtree com of the root)
    moved to the joint origin and rotated into the joint frame, against Pinocchio's data.f,
    relative to the largest force of the state."""
    worst, scale = 0.0, 1e-300
    for b in range(1, mj.nbody):
        if mj.body_jntnum[b] == 0:
            continue
        j = int(built.body_joint[b])
        oMi = data.oMi[j]
        com = d.subtree_com[mj.body_rootid[b]]
        torque, force = d.cfrc_int[b, :3], d.cfrc_int[b, 3:]
        moment = torque + np.cross(com - oMi.translation, force)
        mine = np.concatenate([oMi.rotation.T @ force, oMi.rotation.T @ moment])
        worst = max(worst, np.abs(mine - data.f[j].vector).max())
        scale = max(scale, np.abs(mine).max())
    return worst / scale


def _check(err, mj, built):
    assert err["maps"] < 1e-14, err
    assert err["pose"] < 1e-12, err
    assert err["inertia"] < 1e-12, err
    assert err["M"] < 1e-10, err
    assert err["rnea"] < 1e-10, err
    assert err["cfrc_int"] < 1e-10, err
    assert err["passive"] < 1e-12, err
    total = sum(built.model.inertias[j].mass for j in range(built.model.njoints))
    assert total == pytest.approx(mujoco.mj_getTotalmass(mj), rel=1e-14)


# ------------------------------------------------------------------------------ small models
def test_small_model_matches_mujoco():
    mj = mujoco.MjModel.from_xml_string(SMALL)
    built = build_model(mj, "SMALL")
    err = compare(mj, built)
    _check(err, mj, built)
    model = built.model
    assert [model.names[j] for j in range(1, model.njoints)] == ["b1", "b2", "b3", "b4", "floater", "fc"]
    assert model.joints[2].shortname() == "JointModelComposite"
    assert model.joints[4].shortname() == "JointModelPZ"
    assert model.joints[1].shortname() == "JointModelRevoluteUnaligned"
    assert built.coordinate_names == ("h1", "j_a", "j_b", "j_c", "ball[0]", "ball[1]", "ball[2]", "sl",
                                      "fj[0]", "fj[1]", "fj[2]", "fj[3]", "fj[4]", "fj[5]", "fh")
    names = [f.name for f in model.frames]
    assert "site:s1" in names and "site:#1" in names and "geom:arm" in names and "geom:#1" in names
    assert model.frames[int(built.geom_frame[0])].name == "geom:floor"
    assert model.frames[int(built.body_frame[0])].name == "world"
    assert np.allclose(model.gravity.linear, [0.3, -1, -9.81])
    h1 = built.jnt_idx_v[0]
    assert model.armature[h1] == 0.02 and model.armature[built.jnt_idx_v[3]] == 0.1
    # ref: Pinocchio's angle is qpos - ref; the range follows
    assert model.lowerPositionLimit[0] == pytest.approx(np.radians(-40 - 17), abs=1e-15)
    assert model.upperPositionLimit[0] == pytest.approx(np.radians(60 - 17), abs=1e-15)
    assert built.to_pin_q(mj.qpos0)[0] == 0.0
    # springs are active in the model (a passive force of zero would test nothing)
    assert np.abs(built.joint_passive(built.to_pin_q(mj.qpos0), np.zeros(mj.nv))).max() > 0.1


@pytest.mark.parametrize("joints", [
    '<joint type="hinge" pos="0.1 0 0" axis="0 1 1"/><joint type="ball" pos="0 0.2 0.1"/>',
    '<joint type="slide" axis="1 1 0"/><joint type="ball" pos="0 0.2 0.1"/>',
    '<joint type="slide" axis="1 0 0"/><joint type="hinge" pos="0.1 0.1 0" axis="0 0 1" ref="30"/>'
    '<joint type="slide" axis="0 1 0" pos="3 3 3"/>',
])
def test_composites_with_balls_and_slides(joints):
    """A ball after a hinge or a slide, and slides around a hinge (a slide keeps the anchor)."""
    xml = f"""<mujoco><worldbody><body pos="0.1 0.2 0.3" euler="10 20 30">{joints}
              <geom type="box" size=".1 .2 .3" pos="0.1 0 0"/>
              <body pos="0.2 0 0"><joint type="hinge"/><geom size=".1"/></body>
              </body></worldbody></mujoco>"""
    mj = mujoco.MjModel.from_xml_string(xml)
    built = build_model(mj, "composite")
    assert built.model.joints[1].shortname() == "JointModelComposite"
    _check(compare(mj, built, n_states=10), mj, built)


def test_static_model_and_bad_states():
    xml = """<mujoco><worldbody><body pos="0 0 1"><geom size=".1"/><site name="a"/></body>
             </worldbody></mujoco>"""
    mj = mujoco.MjModel.from_xml_string(xml)
    built = build_model(mj, "static")
    assert built.model.nq == 0 and built.joint_passive([], []).shape == (0,)
    d = mujoco.MjData(mj)
    mujoco.mj_kinematics(mj, d)
    data = built.model.createData()
    pin.framesForwardKinematics(built.model, data, np.zeros(0))
    assert np.allclose(data.oMf[int(built.site_frame[0])].translation, d.site_xpos[0], rtol=0, atol=1e-15)
    assert built.model.inertias[0].mass == pytest.approx(mujoco.mj_getTotalmass(mj))
    small = build_model(mujoco.MjModel.from_xml_string(SMALL), "SMALL")
    with pytest.raises(StateError, match="qpos must be 17"):
        small.to_pin_q(np.zeros(3))
    with pytest.raises(StateError, match="finite"):
        small.to_mj_qpos(np.full(17, np.nan))
    with pytest.raises(StateError, match="'ball' has a zero quaternion"):
        small.to_pin_q(np.zeros(17))


def test_free_velocity_needs_the_orientation():
    mj = mujoco.MjModel.from_xml_string(SMALL)
    built = build_model(mj, "SMALL")
    with pytest.raises(StateError, match="qpos is needed.*'fj'"):
        built.to_pin_v(np.zeros(mj.nv))


@pytest.mark.parametrize("body, message", [
    ('<body mocap="true"><geom size=".1"/></body>', "mocap"),
    ('<body gravcomp="1"><joint/><geom size=".1"/></body>', "gravcomp"),
    ('<body name="B"><joint name="J" frictionloss="0.1"/><geom size=".1"/></body>', "'J'.*frictionloss"),
    ('<body><joint name="S" type="ball" stiffness="1"/><geom size=".1"/></body>', "'S'.*stiffness"),
    ('<body><freejoint name="F"/><joint/><geom size=".1"/></body>', ""),
])
def test_refusals(body, message):
    xml = f"<mujoco><worldbody>{body}</worldbody></mujoco>"
    try:
        mj = mujoco.MjModel.from_xml_string(xml)
    except ValueError:
        return  # MuJoCo itself refuses it
    with pytest.raises(ModelError, match=message):
        build_model(mj, "test")


def test_free_joint_armature():
    """Armature on a free joint's rotations maps exactly; on its translations it is refused."""
    xml = """<mujoco><worldbody><body><joint name="F" type="free" armature="0.3"/><geom size=".1"/>
             </body></worldbody></mujoco>"""
    with pytest.raises(ModelError, match="'F'.*armature"):
        build_model(mujoco.MjModel.from_xml_string(xml), "test")
    mj = mujoco.MjModel.from_xml_string(xml)
    mj.dof_armature[:3] = 0.0
    mujoco.mj_setConst(mj, mujoco.MjData(mj))  # constants derived from the armature
    built = build_model(mj, "test")
    assert list(built.model.armature) == [0, 0, 0, 0.3, 0.3, 0.3]
    _check(compare(mj, built, n_states=10), mj, built)


def test_mujoco_refuses_massless_moving_bodies():
    xml = """<mujoco><worldbody><body><joint/><body pos="0 0 1"><joint/>
             <geom size=".1" mass="1"/></body></body></worldbody></mujoco>"""
    with pytest.raises(ValueError, match="mass and inertia of moving bodies"):
        mujoco.MjModel.from_xml_string(xml)


# ---------------------------------------------------------------------------- MyoSuite models
@pytest.mark.parametrize("name, nv", [("myoelbow", 1), ("myoelbow_2dof", 2), ("myofinger", 4)])
def test_myosuite_legacy_models(name, nv):
    mj = _myo(name)
    built = build_model(mj, name)
    assert built.model.nv == nv
    err = compare(mj, built)
    _check(err, mj, built)


def test_myoarm_r(myoarm):
    built = build_model(myoarm, "myoarm_r")
    assert built.model.nv == 38 and myoarm.nbody == 53
    assert not np.any(myoarm.tendon_stiffness) and not np.any(myoarm.tendon_damping)
    err = compare(myoarm, built)
    _check(err, myoarm, built)
    shoulder = built.model.joints[int(built.body_joint[19])]  # scapula_r: three hinges
    assert shoulder.shortname() == "JointModelComposite" and shoulder.nv == 3


# ------------------------------------------------------------------------ vendored MyoSuite files
@pytest.fixture(scope="module")
def vendor_tool():
    sys.path.insert(0, str(REPO / "tools"))
    try:
        import vendor_myosuite
    finally:
        sys.path.pop(0)
    return vendor_myosuite


@pytest.mark.parametrize("file", ["myoelbow_1dof6muscles.xml", "myoelbow_2dof6muscles.xml", "myoarm_r.xml"])
def test_vendored_file_equals_original(file, vendor_tool, myoarm, tmp_path):
    text = (VENDORED / file).read_text()
    assert "file=" not in text and "meshdir" not in text and "mesh=" not in text
    (tmp_path / file).write_text(text)  # alone in a folder: nothing else to find
    mine = mujoco.MjModel.from_xml_path(str(tmp_path / file))
    original = myoarm if file == "myoarm_r.xml" else vendor_tool.load_original(file).compile()
    assert mine.nmesh == 0 and not np.any(mine.geom_type == mujoco.mjtGeom.mjGEOM_MESH)
    for count in ("nbody", "njnt", "nsite", "ntendon", "nwrap", "nu", "neq", "nkey"):
        assert getattr(mine, count) == getattr(original, count), count
    assert np.abs(mine.body_mass - original.body_mass).max() <= 1e-12
    assert np.abs(mine.body_inertia - original.body_inertia).max() <= 1e-12
    d0, d1 = mujoco.MjData(original), mujoco.MjData(mine)
    rng = np.random.default_rng(3)
    for _ in range(20):
        d0.qpos[:] = d1.qpos[:] = random_state(original, rng)[0]
        mujoco.mj_forward(original, d0)
        mujoco.mj_forward(mine, d1)
        m0, m1 = np.zeros((original.nv,) * 2), np.zeros((original.nv,) * 2)
        mujoco.mj_fullM(original, d0, m0)
        mujoco.mj_fullM(mine, d1, m1)
        assert np.abs(m1 - m0).max() <= 1e-12 * np.abs(m0).max()
        assert np.abs(d1.ten_length - d0.ten_length).max() <= 1e-12
        assert np.abs(d1.site_xpos - d0.site_xpos).max() <= 1e-12


def test_joint_passive_of_hinges_and_slides_equals_mujocos():
    """The hinge-and-slide fast path of joint_passive (springs with springref on ref-shifted joints,
    dampers) against MuJoCo's qfrc_spring + qfrc_damper."""
    xml = """<mujoco><worldbody><body name="a"><geom size="0.1" mass="1"/>
      <joint name="h1" type="hinge" axis="0 1 0" ref="0.3" springref="0.7" stiffness="4" damping="0.5"/>
      <body name="b" pos="0 0 0.3"><geom size="0.1" mass="1"/>
        <joint name="s1" type="slide" axis="1 0 0" stiffness="2" springref="-0.1" damping="0.2"/>
        <joint name="h2" type="hinge" axis="0 0 1" pos="0.1 0 0" damping="1.5"/></body></body>
      </worldbody></mujoco>"""
    mj = mujoco.MjModel.from_xml_string(xml)
    built = build_model(mj, "springs")
    assert built._hinges_and_slides
    d = mujoco.MjData(mj)
    rng = np.random.default_rng(3)
    for _ in range(20):
        d.qpos[:] = rng.uniform(-1, 1, mj.nq)
        d.qvel[:] = rng.normal(size=mj.nv)
        mujoco.mj_forward(mj, d)
        ours = built.joint_passive(built.to_pin_q(d.qpos), built.to_pin_v(d.qvel))
        ref = built.to_pin_v(d.qfrc_spring + d.qfrc_damper)
        assert np.abs(ours - ref).max() < 1e-12
