"""MJCF robots against MuJoCo 4.0 itself: tendon lengths and moment arms over wraps and pulleys, muscle
tensions at given activations, and interaction wrenches with wrapped muscles pressing on bones.

MyoSuite's models come from ``myo_sim`` (the test extra); the arms, hands, legs and torsos are composed
in code by MyoSuite and compiled by MuJoCo. Every comparison runs on every MyoSuite model that loads (the
21 "loaded" rows of docs/musculoskeletal.md's table, ``tools/myosuite_table.py``'s ``LOADED``), at 50
random states per model.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")
myo_sim = pytest.importorskip("myo_sim", reason="MyoSuite's models (pip install myo-sim) are the references")

from mcdm_pin.robot import Robot  # noqa: E402
from mcdm_pin.model.terms import TermsEvaluator  # noqa: E402

STATES = 50
# every model that loads: elbows, a finger with pulleys and one with motors on its tendons, the arm
# (couplings), the hands, the legs (a free root, couplings; the OSL prosthesis's joint motors), the
# torsos (208-414 muscles), both arms and the full body; the elbows with an exoskeleton's motor without
# a control range (an unbounded joint actuator)
MODELS = ("myoelbow", "myoelbow_2dof", "myofinger", "motorfinger", "myoarm_r", "myohand", "myolegs", "myotorso",
          "myolegs_osl", "myohand_l", "myoarms", "myohands", "myolegs26", "myolegs_abdomen", "myotorso_abdomen",
          "myotorso_arm_r", "myotorso_arms", "myofullbody", "myoelbow_exo",
          "legacy/elbow/myoelbow_1dof6muscles_1dofSoftexo_Ideal.xml",
          "legacy/elbow/myoelbow_1dof6muscles_1dofSoftexo_sim2.xml")


def _compile(name):
    if name == "motorfinger":
        return mujoco.MjModel.from_xml_path(str(myo_sim.get_xml_path("myofinger")).replace("myofinger_v0",
                                                                                          "motorfinger_v0"))
    if name.endswith(".xml"):  # (a whole model of myo_sim's legacy folder)
        return mujoco.MjModel.from_xml_path(str(myo_sim.get_path(name)))
    if name == "myohand_l":  # (a fragment: no load_spec name)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return myo_sim.FRAGMENT_SPEC_BUILDERS[name]().compile()
    # composed in code by MyoSuite
    if name not in ("myoelbow", "myoelbow_2dof", "myoelbow_exo", "myofinger", "myolegs_osl"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return myo_sim.load_spec(name).compile()
    return mujoco.MjModel.from_xml_path(str(myo_sim.get_xml_path(name)))


@pytest.fixture(scope="module", params=MODELS)
def case(request, tmp_path_factory):
    import os

    here = os.getcwd()
    os.chdir(tmp_path_factory.mktemp("mujoco"))  # MuJoCo writes MUJOCO_LOG.TXT where it runs
    try:
        mj = _compile(request.param)
        mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        robot = Robot.from_mujoco(mj, request.param, request.param)
        yield request.param, mj, robot, TermsEvaluator(robot)
    finally:
        os.chdir(here)


def _tendon_J(mj, d) -> np.ndarray:
    """MuJoCo's ``ten_J`` as a dense (ntendon, nv) array (it is stored sparse for large models)."""
    if d.ten_J.size == mj.ntendon * mj.nv and not mj.ten_J_rownnz.size:
        return d.ten_J.reshape(mj.ntendon, mj.nv)
    J = np.zeros((mj.ntendon, mj.nv))
    for t in range(mj.ntendon):
        a, n = mj.ten_J_rowadr[t], mj.ten_J_rownnz[t]
        J[t, mj.ten_J_colind[a:a + n]] = d.ten_J[a:a + n]
    return J


def _states(mj, robot, rng):
    """Random MuJoCo states within the joint ranges that keep the couplings, with random speeds and
    activations."""
    maps = robot.source.maps
    for _ in range(STATES):
        qpos = mj.qpos0.copy()
        for j in range(mj.njnt):
            a = mj.jnt_qposadr[j]
            if mj.jnt_type[j] in (mujoco.mjtJoint.mjJNT_FREE, mujoco.mjtJoint.mjJNT_BALL):
                k = 3 if mj.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE else 0
                qpos[a:a + k] += rng.normal(0.0, 0.1, k)
                quat = rng.normal(size=4)
                qpos[a + k:a + k + 4] = quat / np.linalg.norm(quat)
                continue
            lo, hi = mj.jnt_range[j] if mj.jnt_limited[j] else (-1.0, 1.0)
            qpos[a] = rng.uniform(lo, hi)
        q = maps.to_pin_q(qpos)
        v = rng.normal(0.0, 1.0, mj.nv)
        if robot.couplings is not None:
            q, v, _ = robot.couplings.fill(q, v)
        yield maps.to_mj_qpos(q), maps.to_mj_qvel(v, q), rng.uniform(0.0, 1.0, mj.nu)


def _set_controls(mj, d, act):
    """``act`` (nu,) in [0, 1]: each muscle's activation, each other actuator's control as that share of
    its control range (without a control range: ``2 act - 1``, a control in [-1, 1])."""
    for i in range(mj.nu):
        if mj.actuator_actadr[i] >= 0:
            d.act[mj.actuator_actadr[i]] = act[i]
        elif mj.actuator_ctrllimited[i]:
            lo, hi = mj.actuator_ctrlrange[i]
            d.ctrl[i] = lo + act[i] * (hi - lo)
        else:
            d.ctrl[i] = 2.0 * act[i] - 1.0


def _cable_tendons(mj, robot):
    acts = [mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_ACTUATOR, n) for n in robot.cable_names]
    return np.array(acts), np.array([int(mj.actuator_trnid[a, 0]) for a in acts])


def test_lengths_moment_arms_and_muscle_tensions_equal_mujocos(case):
    name, mj, robot, ev = case
    d = mujoco.MjData(mj)
    acts, tendons = _cable_tendons(mj, robot)
    maps = robot.source.maps
    err_l = err_L = err_f = 0.0
    for qpos, qvel, act in _states(mj, robot, np.random.default_rng(1)):
        d.qpos[:], d.qvel[:] = qpos, qvel
        _set_controls(mj, d, act)
        mujoco.mj_fwdPosition(mj, d)
        mujoco.mj_fwdVelocity(mj, d)
        mujoco.mj_fwdActuation(mj, d)
        q, v = maps.to_pin_q(qpos), maps.to_pin_v(qvel, qpos)
        a = None if robot.couplings is None else robot.couplings.fill(q, v, np.zeros(robot.nv))[2]
        t = ev(q, v, a)  # accelerations that keep the couplings
        J = _tendon_J(mj, d)[tendons]
        err_l = max(err_l, np.max(np.abs(t.lengths - d.ten_length[tendons]) / np.abs(d.ten_length[tendons])))
        err_L = max(err_L, np.max(np.abs(t.L_full - J)) / np.abs(J).max())
        f_mj = -d.actuator_force[acts] * mj.actuator_gear[acts, 0]
        if t.muscles is not None:
            k = robot.cables.muscle_index
            f = t.muscles.passive + t.muscles.gain * act[acts[k]]
            err_f = max(err_f, np.max(np.abs(f - f_mj[k])) / max(1.0, np.abs(f_mj[k]).max()))
    assert err_l < 1e-9, (name, err_l)
    assert err_L < 1e-9, (name, err_L)
    assert err_f < 1e-9, (name, err_f)


def test_interaction_wrenches_with_wrapped_muscles_equal_cfrc_int(case):
    """MuJoCo's forward dynamics at a random state and activation gives ``qacc``; its ``cfrc_int``
    (muscle forces included) moved to each joint point and turned into the child frame equals
    ``u + R^T f`` at that acceleration with the muscles' tensions."""
    name, mj, robot, ev = case
    d = mujoco.MjData(mj)
    acts, _ = _cable_tendons(mj, robot)
    maps = robot.source.maps
    body_of_joint = {int(maps.body_joint[b]): b for b in range(1, mj.nbody) if mj.body_jntnum[b]}
    worst = 0.0
    for qpos, qvel, act in _states(mj, robot, np.random.default_rng(2)):
        d.qpos[:], d.qvel[:] = qpos, qvel
        _set_controls(mj, d, act)
        mujoco.mj_forward(mj, d)
        mujoco.mj_rnePostConstraint(mj, d)
        q = maps.to_pin_q(qpos)
        t = ev(q, maps.to_pin_v(qvel, qpos), maps.to_pin_a(d.qacc, qpos, qvel), checked=True)
        f = -d.actuator_force[acts] * mj.actuator_gear[acts, 0]
        p = t.wrenches(f)
        for k, joint in enumerate(robot.joints):
            b = body_of_joint[joint.child_id]
            oMi = ev.data.oMi[joint.child_id]
            c = d.subtree_com[mj.body_rootid[b]]
            F = d.cfrc_int[b, 3:]
            M = d.cfrc_int[b, :3] + np.cross(c - oMi.translation, F)
            ref = np.concatenate([oMi.rotation.T @ F, oMi.rotation.T @ M])
            scale = max(1.0, np.abs(ref).max())
            worst = max(worst, np.max(np.abs(p[k] - ref)) / scale)
    assert worst < 1e-9, (name, worst)
