r"""The closed loop: reference -> controller (law + force distribution) -> MuJoCo plant -> sensors.

:func:`run_loop` runs ``N`` ticks of ``dt``: at tick ``k`` (time ``t_k = k dt``) it measures the plant,
asks the controller for tensions against the reference at ``t_k`` and holds them on the plant until
``t_{k+1}``. The reference is sampled once before the loop (a stored trajectory, as on a real
controller). Before the first tick the controller is warmed (``warm``:
:meth:`~mcdm_pin.control.controller.Controller.warm`, every solver stage and a few ticks run once, so
that no first call falls inside a tick) and the per-tick records are written once (no page fault of
their first write in the loop). The loop runs under :class:`~mcdm_pin.control.realtime.Conditions`:
the garbage collector frozen and disabled by default (``gc``; a full collection of this process's
objects takes 50-150 ms, one of a frozen heap microseconds), optionally pinned to a core (``cpu``),
in ``SCHED_FIFO`` (``fifo_priority``; Linux, with the permission; the paced ticks only, the previous
class restored afterwards), with its memory locked (``lock_memory``). With ``realtime`` the loop keeps
wall-clock time as a controller does: tick ``k`` starts at ``k dt`` after the first (the process
sleeps for the rest of each period, polling the clock for its last ``spin_s``). A tick that starts
late within its period starts at once; one whose whole period has passed (the loop fell behind: the
simulated plant's step, the records and the machine's other processes share the period) waits for
the next period boundary, and the periods passed are counted (``skipped``), as a controller's timer
counts its overruns: the loop does not run back to back to catch up, which on a loaded machine is
what gets a process preempted for whole time slices (below). The plant advances ``dt`` per tick
whatever the wall clock did. A process that sleeps between ticks is woken promptly by the operating
system's scheduler; one that computes without pause (the loop run as fast as possible) is preempted
for whole time slices (4 ms) when the machine is loaded. Each tick is probed
(:class:`~mcdm_pin.control.realtime.Probe`): its CPU time, its wait on the run queue, its page faults
and garbage collections tell a late tick's causes apart (:meth:`LoopResult.causes`).

**Tracking error** at tick ``k``: ``e = q_r(t_k) (-) q(t_k)`` (``pin.difference``, exact state),
per physical joint the norm of its rotational part (deg: a revolute angle, a ball's or free joint's
rotation vector) and of its translational part (mm: a prismatic joint, a free joint's position in its
child frame). :meth:`LoopResult.summary` gives their RMS over ticks and joints and their peak.

**Model errors.** :func:`scaled_masses` gives the controller a robot whose every body is ``factor``
times as heavy (mass and inertia about the centre of mass scaled alike: the same shapes, denser).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import ProblemError
from ..robot import Robot
from .realtime import Conditions, Probe, wait_until


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
    part); the deadline and the plant's ``clamped`` count. The probes of each tick
    (:class:`~mcdm_pin.control.realtime.Probe`): ``start_late_s`` (a paced tick's start after its
    instant), ``wait_s`` (run-queue wait during the tick), ``switches`` (involuntary context
    switches), ``faults`` (page faults) and ``collections`` (garbage collections) during the tick;
    ``collections_between``: young-generation collections between ticks; ``skipped``: the periods
    skipped before a paced tick (module docstring)."""

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
    start_late_s: np.ndarray | None = None
    wait_s: np.ndarray | None = None
    switches: np.ndarray | None = None
    faults: np.ndarray | None = None
    collections: np.ndarray | None = None
    collections_between: int = 0
    skipped: np.ndarray | None = None

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
                    clamped=self.clamped, **self.causes())

    def causes(self) -> dict:
        """Where the late ticks' time went (:mod:`mcdm_pin.control.realtime`): ``misses_cpu`` (the
        tick's own CPU time over the deadline), ``misses_queue`` (CPU time plus run-queue wait over
        it: other processes ran), ``misses_other`` (neither: blocked, or interrupts accounted apart); the late ticks
        with a page fault, a garbage collection, an involuntary switch; per tick totals of faults and
        collections; the paced ticks' start delay p50/p99/max (ms), the periods they skipped, and
        ``late_from_instant``: the ticks whose start delay plus latency exceeds the deadline (late
        counted from the tick's instant, not from its start). Empty without probes."""
        if self.wait_s is None:
            return {}
        late = self.latency_s > self.deadline_s
        on_cpu = self.cpu_s > self.deadline_s
        queue = ~on_cpu & (self.cpu_s + self.wait_s > self.deadline_s)
        ms = lambda x, p: float(np.percentile(x, p) * 1e3)  # noqa: E731
        return dict(misses_queue=int(np.sum(late & queue)), misses_other=int(np.sum(late & ~on_cpu & ~queue)),
                    late_with_fault=int(np.sum(late & (self.faults > 0))),
                    late_with_gc=int(np.sum(late & (self.collections > 0))),
                    late_with_switch=int(np.sum(late & (self.switches > 0))),
                    faults=int(self.faults.sum()), collections_in_ticks=int(self.collections.sum()),
                    collections_between=self.collections_between,
                    start_late_p50_ms=ms(self.start_late_s, 50), start_late_p99_ms=ms(self.start_late_s, 99),
                    start_late_max_ms=float(self.start_late_s.max() * 1e3),
                    periods_skipped=int(self.skipped.sum()), ticks_after_skip=int(np.sum(self.skipped > 0)),
                    late_from_instant=int(np.sum(self.start_late_s + self.latency_s > self.deadline_s)))


def run_loop(controller, plant, reference, duration: float, dt: float | None = None, gc: str = "freeze",
             realtime: bool = False, fifo_priority: int | None = None, cpu: int | None = None,
             spin_s: float = 0.0, warm: bool = True, lock_memory: bool = False) -> LoopResult:
    """Run the closed loop for ``duration`` s (module docstring).

    Args:
        controller: a :class:`~mcdm_pin.control.controller.Controller`.
        plant: a :class:`~mcdm_pin.control.plant.MujocoPlant` (its ``dt`` is the tick).
        reference: a plan ``t -> (q, v, a)`` (Pinocchio's coordinates), e.g.
            :func:`mcdm_pin.trajectory.plan`.
        gc: the garbage collector during the loop: ``"freeze"`` (default), ``"off"`` or ``"on"``
            (:class:`~mcdm_pin.control.realtime.Conditions`).
        realtime: pace the ticks on the wall clock (module docstring); off: as fast as possible.
        fifo_priority: run the ticks in ``SCHED_FIFO`` at this priority (1-99; with ``realtime`` only:
            a real-time loop that never sleeps would hold a core).
        cpu: pin the loop to this core; ``lock_memory``: lock its pages (``mlockall``).
        spin_s: with ``realtime``, poll the clock for the last ``spin_s`` before each tick instead of
            sleeping (:func:`~mcdm_pin.control.realtime.wait_until`).
        warm: run every stage of the solver chain and a few ticks before the loop
            (:meth:`~mcdm_pin.control.controller.Controller.warm`).

    Raises:
        ProblemError: ``fifo_priority`` without ``realtime``, or the system refuses a condition.
    """
    if fifo_priority is not None and not realtime:
        raise ProblemError("run_loop: fifo_priority needs realtime=True (a SCHED_FIFO loop that never sleeps "
                           "would hold a core)")
    if not (np.isfinite(spin_s) and spin_s >= 0):
        raise ProblemError(f"run_loop: spin_s: expected a time >= 0 s, got {spin_s!r}")
    dt = plant.dt if dt is None else dt
    if abs(dt - plant.dt) > 1e-15:
        raise ProblemError(f"run_loop: dt {dt!r} differs from the plant's period {plant.dt!r}")
    n = int(round(duration / dt))
    if n < 1:
        raise ProblemError(f"run_loop: expected a duration of at least one tick ({dt} s), got {duration!r}")
    t = np.arange(n) * dt
    Q_r, V_r, A_r = sample(reference, t)
    conditions = Conditions(gc=gc, cpu=cpu, fifo_priority=fifo_priority, lock_memory=lock_memory)
    plant.reset(Q_r[0], V_r[0])
    q_m, v_m = plant.measure()
    if warm:
        controller.warm(q_m, v_m, Q_r[0], V_r[0], A_r[0])
    controller.start(q_m, v_m, Q_r[0], V_r[0], A_r[0])
    rec = _Record(n, plant.robot.nq, plant.robot.m)
    with controller.ident.blas_limit(), conditions:
        _ticks(controller, plant, (Q_r, V_r, A_r), dt, rec, conditions, realtime, spin_s)
    rot, lin = tracking_errors(plant.robot, rec.Q, Q_r)
    return LoopResult(t, rec.Q, Q_r, rec.F, rec.lat, rec.dist, rec.cpu, rec.status.astype(str),
                      rec.stage.astype(str), rec.fallback.astype(str), rot, lin, controller.deadline_s,
                      plant.clamped, rec.start_late, rec.wait, rec.switches, rec.faults, rec.collections,
                      conditions.collections, rec.skipped)


class _Record:
    """The loop's per-tick records, every page written once before the first tick (no page fault of
    a first write inside the loop)."""

    def __init__(self, n: int, nq: int, m: int):
        self.Q, self.F = np.zeros((n, nq)), np.zeros((n, m))
        self.lat, self.dist, self.cpu, self.start_late, self.wait = (np.zeros(n) for _ in range(5))
        self.switches, self.faults, self.collections, self.skipped = (np.zeros(n, dtype=np.int64) for _ in range(4))
        for a in (self.Q, self.F, self.lat, self.dist, self.cpu, self.start_late, self.wait, self.switches,
                  self.faults, self.collections, self.skipped):
            a.fill(1)  # (np.zeros maps fresh pages lazily: touch them)
            a.fill(0)
        self.status, self.stage, self.fallback = (np.full(n, "", dtype=object) for _ in range(3))


def _ticks(controller, plant, refs, dt, rec, conditions, realtime, spin_s) -> None:
    """The ``len(rec.lat)`` ticks of :func:`run_loop`, with the probes around each tick."""
    Q_r, V_r, A_r = refs
    probe = Probe()
    try:
        start, skipped = time.perf_counter() + dt, 0
        for k in range(len(rec.lat)):
            if realtime:
                target = start + (k + skipped) * dt
                behind = time.perf_counter() - target
                if behind >= dt:  # the tick's whole period has passed: on to the next period boundary
                    rec.skipped[k] = int(behind // dt) + 1
                    skipped += rec.skipped[k]
                    target += rec.skipped[k] * dt
                wait_until(target, spin_s)
                rec.start_late[k] = time.perf_counter() - target
            rec.Q[k] = plant.state()[0]
            q_m, v_m = plant.measure()
            w0, s0, p0, c0 = probe.read()
            tick = controller.tick(q_m, v_m, Q_r[k], V_r[k], A_r[k])
            w1, s1, p1, c1 = probe.read()
            plant.step(tick.f)
            rec.F[k], rec.lat[k], rec.dist[k], rec.cpu[k] = tick.f, tick.latency_s, tick.distribution_s, tick.cpu_s
            rec.wait[k], rec.switches[k] = (w1 - w0) * 1e-9, s1 - s0
            rec.faults[k], rec.collections[k] = p1 - p0, c1 - c0
            rec.status[k], rec.stage[k], rec.fallback[k] = tick.status, tick.stage, tick.fallback or ""
            slack = (start + (k + 1) * dt - time.perf_counter()) if realtime else controller.deadline_s - tick.latency_s
            conditions.between_ticks(slack)
    finally:
        probe.close()


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
