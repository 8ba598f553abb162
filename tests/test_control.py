"""The control loop (mcdm_pin.control) and its plant's model (mcdm_pin.export.mjcf).

The MJCF export is checked against MuJoCo itself: the exported model's ``mj_fullM``, ``qfrc_bias``,
``ten_length``, ``ten_J`` and ``qfrc_actuator`` equal our Robot's M, h, cable lengths, L and ``-L^T f``
at random states (mapped between the two coordinate conventions), on the neck (24 revolute joints in
8 massless-grouped bodies) and on CoGiRo (a platform on a free joint)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from .conftest import REPO

mujoco = pytest.importorskip("mujoco", reason="pip install -e '.[mjcf]'")

from mcdm_pin import Robot  # noqa: E402
from mcdm_pin.control import (Controller, JointSpaceLaw, MujocoPlant, TaskSpaceLaw, back_and_forth,  # noqa: E402
                              pid_gains, reverse, run_loop, scaled_masses, time_scaled)
from mcdm_pin.export.mjcf import export_mjcf  # noqa: E402
from mcdm_pin.model.terms import TermsEvaluator  # noqa: E402
from mcdm_pin.trajectory import plan  # noqa: E402

NECK = REPO / "robots" / "caspr" / "8S_neck" / "8S_neck.yaml"
COGIRO = REPO / "robots" / "caspr" / "CoGiRo" / "CoGiRo.yaml"


@pytest.fixture(scope="module")
def neck():
    return Robot.load(NECK)


@pytest.fixture(scope="module")
def cogiro():
    return Robot.load(COGIRO)


def _ten_J(mj, d) -> np.ndarray:
    """MuJoCo 4.0 stores ``ten_J`` as compressed rows: expand it to (ntendon, nv)."""
    J = np.zeros((mj.ntendon, mj.nv))
    for i in range(mj.ntendon):
        a, n = mj.ten_J_rowadr[i], mj.ten_J_rownnz[i]
        J[i, mj.ten_J_colind[a:a + n]] = d.ten_J[a:a + n]
    return J


@pytest.mark.parametrize("name", ["neck", "cogiro"])
def test_mjcf_export_matches_our_terms(name, request, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    robot = request.getfixturevalue(name)
    ex = export_mjcf(robot)
    mj = ex.compile()
    d = mujoco.MjData(mj)
    assert (mj.nq, mj.nv, mj.ntendon, mj.nu) == (robot.nq, robot.nv, robot.m, robot.m)
    assert mj.nbody == 1 + sum(1 for j in robot.joints)  # one MuJoCo body per physical joint
    evaluate = TermsEvaluator(robot)
    data = robot.model.createData()
    rng = np.random.default_rng(7)
    for _ in range(4):
        x = rng.uniform(-0.4, 0.4, robot.nv)
        if name == "cogiro":
            x[:3] = rng.uniform(-2.0, 2.0, 3) + [0.0, 0.0, 3.0]
        q = pin.integrate(robot.model, pin.neutral(robot.model), x)
        v = rng.normal(size=robot.nv)
        f = robot.f_min + rng.uniform(1.0, 50.0, robot.m)  # within the motors' ctrlrange
        d.qpos[:], d.qvel[:], d.ctrl[:] = ex.qpos(q), ex.qvel(q, v), f
        mujoco.mj_forward(mj, d)
        M_mj = np.zeros((mj.nv, mj.nv))
        mujoco.mj_fullM(mj, d, M_mj)
        T = ex.T(q)
        terms = evaluate(q, v, np.zeros(robot.nv))
        M = pin.crba(robot.model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        h = ex.to_pin_force(q, d.qfrc_bias + M_mj @ ex.bias_correction(q, v))
        scale = max(1.0, np.abs(M).max())
        assert np.abs(T.T @ M_mj @ T - M).max() <= 1e-9 * scale
        assert np.abs(h - terms.tau).max() <= 1e-9 * max(1.0, np.abs(terms.tau).max())
        assert np.abs(d.ten_length - terms.lengths).max() <= 1e-9
        assert np.abs(_ten_J(mj, d) @ T - terms.L).max() <= 1e-9
        # a positive command pulls: the motors' generalised force is our -L^T f
        assert np.abs(ex.to_pin_force(q, d.qfrc_actuator) + terms.L.T @ f).max() <= 1e-9 * f.max()
        # the state maps round-trip
        assert np.abs(pin.difference(robot.model, ex.q(d.qpos), q)).max() <= 1e-12
        assert np.abs(ex.v(d.qpos, d.qvel) - v).max() <= 1e-12


def _cogiro_loop(robot, duration, deadline_s=1e-3):
    go = time_scaled(plan(robot, robot.sidecar.trajectories["general_1"]), 1.25)
    reference = back_and_forth(go, reverse(go, 5.0), 5.0)
    model = scaled_masses(robot, 1.05)
    law = TaskSpaceLaw(model, "CoGiRo", **pid_gains(50.0), dt=1e-3)
    controller = Controller(model, 1, law, deadline_s=deadline_s)
    plant = MujocoPlant(robot, dt=1e-3, noise_q=1e-4, noise_v=1e-3, seed=1)
    return run_loop(controller, plant, reference, duration), controller


def test_closed_loop_tracks(cogiro, tmp_path, monkeypatch):
    """0.3 s at 1 kHz, masses 5 % off, sensor noise 0.1 mm / 1e-4 rad: the platform stays within
    1 mm and 0.05 deg of its reference (measured: ~0.06 mm, ~0.005 deg), within the cable bounds.
    The trajectory starts at the edge of the workspace (cable 5 at f_min): there the noise can ask
    for an acceleration no tension gives (one tick of this seed), a counted 'infeasible' fallback."""
    monkeypatch.chdir(tmp_path)
    res, controller = _cogiro_loop(cogiro, 0.3, deadline_s=1.0)  # a deadline that is never missed here
    s = res.summary()
    assert s["ticks"] == 300 and s["misses"] == 0
    assert set(s["fallback_reasons"]) <= {"infeasible"} and s["fallbacks"] <= 3
    assert s["fallbacks"] == int(np.sum(res.status != "optimal")) == sum(controller.fallbacks.values())
    assert s["peak_lin_mm"] < 1.0 and s["peak_rot_deg"] < 0.05
    assert np.all(res.f >= cogiro.f_min - 1e-9) and np.all(res.f <= cogiro.f_max + 1e-9)
    assert res.clamped == 0


def test_fallback_on_an_impossible_deadline(cogiro, tmp_path, monkeypatch):
    """A deadline of 1 ns is missed at every tick: every tick falls back to the previous forces (those of
    the untimed first solve), and every one is counted."""
    monkeypatch.chdir(tmp_path)
    res, controller = _cogiro_loop(cogiro, 0.02, deadline_s=1e-9)
    s = res.summary()
    assert s["misses"] == 20 and s["fallbacks"] == 20 and s["fallback_reasons"] == {"late": 20}
    assert s["longest_fallback_run"] == 20
    assert controller.misses == 20 and controller.fallbacks["late"] == 20
    assert np.all(res.f == res.f[0])


def test_fallback_on_an_infeasible_instant(neck):
    """An acceleration the cables cannot give (1e6 rad/s^2): the distribution is infeasible, the tick
    applies the previous forces and counts an 'infeasible' fallback; the next feasible tick recovers."""
    law = JointSpaceLaw(neck, kp=0.0, kd=0.0)
    controller = Controller(neck, 1, law, deadline_s=1.0)
    q, v = pin.neutral(neck.model), np.zeros(neck.nv)
    f0 = controller.start(q, v, q, v, np.zeros(neck.nv)).copy()
    tick = controller.tick(q, v, q, v, np.full(neck.nv, 1e6))
    assert tick.status == "infeasible" and tick.fallback == "infeasible"
    assert np.array_equal(tick.f, f0) and controller.fallbacks == {"infeasible": 1}
    tick = controller.tick(q, v, q, v, np.zeros(neck.nv))
    assert tick.fallback is None and tick.status == "optimal"
    assert np.abs(tick.f - f0).max() <= 1e-6


def test_mjcf_export_refuses_what_it_cannot_write(tmp_path, monkeypatch):
    """A massless moving body (MuJoCo refuses it) is refused, naming its joint."""
    from mcdm_pin.exceptions import ModelError
    from mcdm_pin.model.cables import RoutePoint

    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRX(), pin.SE3.Identity(), "hinge")
    model.appendBodyToJoint(j1, pin.Inertia(1.0, np.zeros(3), np.eye(3) * 0.1), pin.SE3.Identity())
    model.addBodyFrame("link", j1, pin.SE3.Identity(), 0)
    j2 = model.addJoint(j1, pin.JointModelRY(), pin.SE3(np.eye(3), np.array([0.0, 0.0, 1.0])), "tip")
    model.addBodyFrame("tip_link", j2, pin.SE3.Identity(), 0)
    cables = [dict(name="c", f_min=0.0, f_max=100.0,
                   route=[RoutePoint("universe", (0.1, 0.0, 0.0)), RoutePoint("link", (0.0, 0.1, 0.5))])]
    with pytest.raises(ModelError, match="'tip'.*massless"):
        export_mjcf(Robot.from_model(model, cables))


def test_fifo_needs_pacing(cogiro, tmp_path, monkeypatch):
    """A SCHED_FIFO loop that never sleeps would hold a core: refused before anything runs."""
    from mcdm_pin.exceptions import ProblemError

    monkeypatch.chdir(tmp_path)
    model = scaled_masses(cogiro, 1.05)
    controller = Controller(model, 1, TaskSpaceLaw(model, "CoGiRo"), deadline_s=1e-3)
    plant = MujocoPlant(cogiro)
    with pytest.raises(ProblemError, match="realtime"):
        run_loop(controller, plant, plan(cogiro, cogiro.sidecar.trajectories["general_1"]), 0.01, fifo_priority=10)


def test_conditions_are_undone():
    """The loop's conditions (gc frozen and disabled, pinned core) hold inside and are undone after,
    also when the body raises; an unknown gc mode is refused."""
    import gc
    import os

    from mcdm_pin.control.realtime import Conditions
    from mcdm_pin.exceptions import ProblemError

    was, cores = gc.isenabled(), os.sched_getaffinity(0)
    with pytest.raises(RuntimeError):
        with Conditions(gc="freeze", cpu=min(cores)):
            assert not gc.isenabled() and gc.get_freeze_count() > 0
            assert os.sched_getaffinity(0) == {min(cores)}
            raise RuntimeError("inside")
    assert gc.isenabled() == was and gc.get_freeze_count() == 0 and os.sched_getaffinity(0) == cores
    with pytest.raises(ProblemError, match="gc"):
        Conditions(gc="sometimes")


def test_probe_and_pacing():
    """wait_until never returns early (sleep, then polling); the probe's counters only grow."""
    import time

    from mcdm_pin.control.realtime import Probe, wait_until

    probe = Probe()
    try:
        before = probe.read()
        for spin in (0.0, 2e-4):
            target = time.perf_counter() + 1e-3
            wait_until(target, spin)
            assert time.perf_counter() >= target
        after = probe.read()
    finally:
        probe.close()
    assert all(b >= a for a, b in zip(before, after))


def test_warm_keeps_the_answers(neck):
    """Controller.warm (every solver stage alone, then ticks) changes nothing of the loop's answers:
    after start, a warmed controller's ticks equal an unwarmed one's, bit for bit."""
    law = lambda: JointSpaceLaw(neck, kp=100.0, kd=20.0)  # noqa: E731
    q0, v0 = pin.neutral(neck.model), np.zeros(neck.nv)
    rng = np.random.default_rng(3)
    states = [(pin.integrate(neck.model, q0, 1e-3 * rng.normal(size=neck.nv)), 1e-2 * rng.normal(size=neck.nv))
              for _ in range(3)]
    forces = []
    for warm in (False, True):
        controller = Controller(neck, 1, law(), deadline_s=1.0)
        if warm:
            controller.warm(q0, v0, q0, v0, np.zeros(neck.nv), ticks=3)
        controller.start(q0, v0, q0, v0, np.zeros(neck.nv))
        forces.append([controller.tick(q, v, q0, v0, np.zeros(neck.nv)).f.copy() for q, v in states])
        assert controller.misses == 0 and not controller.fallbacks
    assert all(np.array_equal(a, b) for a, b in zip(*forces))
