r"""The closed loop: reference -> controller (law + force distribution) -> MuJoCo plant -> sensors.

:func:`run_loop` runs ``N`` ticks of ``dt``: at tick ``k`` (time ``t_k = k dt``) it measures the plant,
asks the controller for tensions against the reference at ``t_k`` and holds them on the plant until
``t_{k+1}``. The reference is sampled once before the loop (a stored trajectory, as on a real
controller). The garbage collector is paused during the loop (``gc_off``), a usual precaution in a
real-time Python loop: a collection can take milliseconds. With ``realtime`` the loop keeps wall-clock
time as a controller does: tick ``k`` starts at ``k dt`` after the first (the process sleeps for the
rest of each period, and a tick that starts late starts at once). A process that sleeps between ticks
is woken promptly by the operating system's scheduler; one that computes without pause (the loop run as
fast as possible) is preempted for whole time slices (4 ms) when the machine is loaded, and those
ticks miss their deadline although their CPU time is well below it (``cpu_s`` tells them apart).
``fifo_priority`` (Linux, with the permission to) runs the paced ticks, and only them, in the
real-time class ``SCHED_FIFO``, as a controller's thread is run: the scheduler then preempts the loop
only for higher real-time priorities; the previous class is restored afterwards.

**Tracking error** at tick ``k``: ``e = q_r(t_k) (-) q(t_k)`` (``pin.difference``, exact state),
per physical joint the norm of its rotational part (deg: a revolute angle, a ball's or free joint's
rotation vector) and of its translational part (mm: a prismatic joint, a free joint's position in its
child frame). :meth:`LoopResult.summary` gives their RMS over ticks and joints and their peak.

**Model errors.** :func:`scaled_masses` gives the controller a robot whose every body is ``factor``
times as heavy (mass and inertia about the centre of mass scaled alike: the same shapes, denser).
"""

from __future__ import annotations

import gc
import os
import time
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import ProblemError
from ..robot import Robot


def scaled_masses(robot, factor: float) -> Robot:
    """A copy of ``robot`` whose bodies' masses and inertias are ``factor`` times the originals."""
    if not (np.isfinite(factor) and factor > 0):
        raise ProblemError(f"scaled_masses: expected a factor > 0, got {factor!r}")
    model = pin.Model(robot.model)
    for i in range(model.njoints):
        I = model.inertias[i]
        model.inertias[i] = pin.Inertia(factor * I.mass, I.lever.copy(), factor * I.inertia)
    return Robot(model, robot.cables, robot.joints, robot.actuators, robot.name, robot.sidecar,
                 robot.urdf_path, robot.couplings, robot.coordinate_names, robot.source, robot.notes)


def sample(reference, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``reference`` (a plan: ``t -> (q, v, a)``) at every time of ``t``: arrays (N, nq), (N, nv), (N, nv)."""
    rows = [reference(float(tk))[:3] for tk in t]
    return tuple(np.array([r[i] for r in rows]) for i in range(3))


def time_scaled(reference, factor: float):
    """The plan ``reference`` run ``factor`` times slower: ``t -> reference(t / factor)`` with rates
    divided by ``factor`` and accelerations by ``factor**2``."""
    def state(t):
        q, v, a = reference(t / factor)[:3]
        return q, v / factor, a / factor**2
    return state


def reverse(reference, duration: float):
    """The plan ``reference`` on ``[0, duration]`` run backwards: ``q(T - t)``, ``-v(T - t)``, ``a(T - t)``."""
    def state(t):
        q, v, a = reference(duration - t)[:3]
        return q, -v, a
    return state


def back_and_forth(go, back, duration: float):
    """A plan alternating two rest-to-rest plans of ``duration`` s each (``go`` then ``back``, ...)."""
    def state(t):
        k, s = divmod(float(t), duration)
        return (go if int(k) % 2 == 0 else back)(s)[:3]
    return state


@dataclass
class LoopResult:
    """Per tick: times ``t`` (N,), exact ``q`` (N, nq), reference ``q_ref``, applied forces ``f``
    (N, m); latencies ``latency_s`` (whole tick, wall time), ``distribution_s`` (the solve alone) and
    ``cpu_s`` (the tick's CPU time: less than its latency when the process was preempted);
    ``status``, ``stage`` (the solver stage that answered) and ``fallback`` (``""``: none) strings;
    ``error_rot_deg``, ``error_lin_mm`` (N, J) per physical joint (NaN where a joint has no such
    part); the deadline and the plant's ``clamped`` count."""

    t: np.ndarray
    q: np.ndarray
    q_ref: np.ndarray
    f: np.ndarray
    latency_s: np.ndarray
    distribution_s: np.ndarray
    cpu_s: np.ndarray
    status: np.ndarray
    stage: np.ndarray
    fallback: np.ndarray
    error_rot_deg: np.ndarray
    error_lin_mm: np.ndarray
    deadline_s: float
    clamped: int = 0

    def summary(self) -> dict:
        """Ticks, deadline misses, answering stages, fallbacks by reason and their longest run of
        consecutive ticks, latency percentiles (ms), RMS/peak errors."""
        fb = self.fallback[self.fallback != ""]
        reasons, counts = np.unique(fb, return_counts=True)

        def rms_peak(e):
            e = e[np.isfinite(e)]
            return (float(np.sqrt(np.mean(e**2))), float(e.max())) if e.size else (float("nan"),) * 2

        rot, lin = rms_peak(self.error_rot_deg), rms_peak(self.error_lin_mm)
        ms = lambda x, p: float(np.percentile(x, p) * 1e3)  # noqa: E731
        stages, n_st = np.unique(self.stage, return_counts=True)
        run = longest = 0
        for fell in self.fallback != "":  # the longest run of consecutive fallbacks
            run = run + 1 if fell else 0
            longest = max(longest, run)
        return dict(ticks=len(self.t), misses=int(np.sum(self.latency_s > self.deadline_s)),
                    stages=dict(zip(stages.tolist(), n_st.tolist())),
                    fallbacks=int(len(fb)), fallback_reasons=dict(zip(reasons.tolist(), counts.tolist())),
                    longest_fallback_run=longest,
                    latency_p50_ms=ms(self.latency_s, 50), latency_p99_ms=ms(self.latency_s, 99),
                    latency_max_ms=float(self.latency_s.max() * 1e3),
                    distribution_p50_ms=ms(self.distribution_s, 50), distribution_p99_ms=ms(self.distribution_s, 99),
                    distribution_max_ms=float(self.distribution_s.max() * 1e3),
                    cpu_p50_ms=ms(self.cpu_s, 50), cpu_p99_ms=ms(self.cpu_s, 99),
                    cpu_max_ms=float(self.cpu_s.max() * 1e3),
                    misses_cpu=int(np.sum(self.cpu_s > self.deadline_s)),
                    rms_rot_deg=rot[0], peak_rot_deg=rot[1], rms_lin_mm=lin[0], peak_lin_mm=lin[1],
                    clamped=self.clamped)


def run_loop(controller, plant, reference, duration: float, dt: float | None = None,
             gc_off: bool = True, realtime: bool = False, fifo_priority: int | None = None) -> LoopResult:
    """Run the closed loop for ``duration`` s (module docstring).

    Args:
        controller: a :class:`~mcdm_pin.control.controller.Controller`.
        plant: a :class:`~mcdm_pin.control.plant.MujocoPlant` (its ``dt`` is the tick).
        reference: a plan ``t -> (q, v, a)`` (Pinocchio's coordinates), e.g.
            :func:`mcdm_pin.trajectory.plan`.
        gc_off: pause the garbage collector during the loop.
        realtime: pace the ticks on the wall clock (module docstring); off: as fast as possible.
        fifo_priority: run the ticks in ``SCHED_FIFO`` at this priority (1-99; with ``realtime`` only:
            a real-time loop that never sleeps would hold a core).

    Raises:
        ProblemError: ``fifo_priority`` without ``realtime``, or the system refuses the class.
    """
    if fifo_priority is not None and not realtime:
        raise ProblemError("run_loop: fifo_priority needs realtime=True (a SCHED_FIFO loop that never sleeps "
                           "would hold a core)")
    dt = plant.dt if dt is None else dt
    if abs(dt - plant.dt) > 1e-15:
        raise ProblemError(f"run_loop: dt {dt!r} differs from the plant's period {plant.dt!r}")
    n = int(round(duration / dt))
    if n < 1:
        raise ProblemError(f"run_loop: expected a duration of at least one tick ({dt} s), got {duration!r}")
    t = np.arange(n) * dt
    Q_r, V_r, A_r = sample(reference, t)
    robot = plant.robot
    plant.reset(Q_r[0], V_r[0])
    q_m, v_m = plant.measure()
    controller.start(q_m, v_m, Q_r[0], V_r[0], A_r[0])
    Q = np.empty((n, robot.nq))
    F = np.empty((n, robot.m))
    lat, dist, cpu = np.empty(n), np.empty(n), np.empty(n)
    status, stage, fallback = (np.empty(n, dtype=object) for _ in range(3))
    was = gc.isenabled()
    gc.collect()
    if gc_off:
        gc.disable()
    previous = _enter_fifo(fifo_priority)
    try:
        with controller.ident.blas_limit():
            start = time.perf_counter()
            for k in range(n):
                if realtime:
                    wait = start + k * dt - time.perf_counter()
                    if wait > 0:
                        time.sleep(wait)
                Q[k] = plant.state()[0]
                q_m, v_m = plant.measure()
                tick = controller.tick(q_m, v_m, Q_r[k], V_r[k], A_r[k])
                plant.step(tick.f)
                F[k], lat[k], dist[k], cpu[k] = tick.f, tick.latency_s, tick.distribution_s, tick.cpu_s
                status[k], stage[k], fallback[k] = tick.status, tick.stage, tick.fallback or ""
    finally:
        if previous is not None:
            os.sched_setscheduler(0, *previous)
        if was:
            gc.enable()
    rot, lin = tracking_errors(robot, Q, Q_r)
    return LoopResult(t, Q, Q_r, F, lat, dist, cpu, status.astype(str), stage.astype(str),
                      fallback.astype(str), rot, lin,
                      controller.deadline_s, plant.clamped)


def _enter_fifo(priority):
    """Switch this thread to ``SCHED_FIFO`` at ``priority``; returns the previous ``(policy, param)``
    (``None`` when ``priority`` is ``None``)."""
    if priority is None:
        return None
    try:
        previous = (os.sched_getscheduler(0), os.sched_getparam(0))
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(int(priority)))
    except (AttributeError, OSError, ValueError) as exc:
        raise ProblemError(f"run_loop: cannot run the ticks in SCHED_FIFO at priority {priority!r}: {exc}") from None
    return previous


def tracking_errors(robot, Q, Q_r) -> tuple[np.ndarray, np.ndarray]:
    """(N, J) rotational (deg) and translational (mm) error norms per physical joint (module docstring)."""
    model = robot.model
    E = np.array([pin.difference(model, q, q_r) for q, q_r in zip(Q, Q_r)])
    n, J = len(Q), len(robot.joints)
    rot, lin = np.full((n, J), np.nan), np.full((n, J), np.nan)
    for j, joint in enumerate(robot.joints):
        lin_idx, rot_idx = [], []
        for pid in joint.pin_ids:
            short = model.joints[pid].shortname()
            iv, nv = model.idx_vs[pid], model.nvs[pid]
            idx = list(range(iv, iv + nv))
            if short == "JointModelFreeFlyer":  # the position's own difference, not log6's coupled part
                iq = model.idx_qs[pid]
                lin[:, j] = 1e3 * np.linalg.norm(Q_r[:, iq:iq + 3] - Q[:, iq:iq + 3], axis=1)
                rot_idx += idx[3:]
            elif short.startswith("JointModelP") or short == "JointModelTranslation":
                lin_idx += idx
            else:
                rot_idx += idx
        if rot_idx:
            rot[:, j] = np.degrees(np.linalg.norm(E[:, rot_idx], axis=1))
        if lin_idx:
            lin[:, j] = 1e3 * np.linalg.norm(E[:, lin_idx], axis=1)
    return rot, lin
