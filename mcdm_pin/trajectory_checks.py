"""Every trajectory of a sidecar checked before a long solve (``mcdm-pin info``): it can be built in
full (lengths of ``q_start``/``q_end``, CSV columns, gimbal lock, finite states), and the problem
``mcdm-pin solve`` would pose is feasible at a handful of its instants.

A pose check is the real thing, not a proxy: the instant's full state ``(q, qd, qdd)`` solved by
:class:`~mcdm_pin.inverse_dynamics.InverseDynamics` as ``solve`` would (case 1, and case 3 when the
sidecar gives a joint a ``cone_deg``), with the diagnosis of what cannot be met. It samples the
trajectory: feasible at every instant checked does not prove every instant feasible.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .exceptions import McdmError

SAMPLES = 11


@dataclass
class TrajectoryCheck:
    """The check of one trajectory.

    Attributes:
        name: the trajectory's name; ``error``: why it cannot be built ('' if it can).
        instants: its number of instants; ``duration``: s.
        checked: indices of the instants solved.
        failures: per case (1 or 3), ``[(t, status, message)]`` at the instants without an answer.
    """

    name: str
    error: str = ""
    instants: int = 0
    duration: float = 0.0
    checked: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    failures: dict = field(default_factory=dict)

    @property
    def level(self) -> str:
        if self.error:
            return "fail"
        return "warn" if any(self.failures.values()) else "ok"

    def text(self) -> str:
        if self.error:
            return f"trajectory {self.name}: cannot be built: {self.error}"
        n = len(self.checked)
        head = f"trajectory {self.name}: {self.instants} instants over {self.duration:g} s"
        parts = []
        previous = None
        for case, bad in self.failures.items():
            if bad and bad == previous:
                parts.append(f"case {case}: the same")
                continue
            previous = bad
            if not bad:
                parts.append(f"case {case} feasible at all {n} instants checked")
                continue
            times = ", ".join(f"{t:g}" for t, _, _ in bad[:8]) + (", ..." if len(bad) > 8 else "")
            t0, status, message = bad[0]
            parts.append(f"case {case} has no answer at {len(bad)} of {n} instants checked (t = {times} s); "
                         f"at t = {t0:g} s: {status}" + (f": {message}" if message else ""))
        return head + "; " + "; ".join(parts)


def check_trajectories(robot, samples: int = SAMPLES) -> list[TrajectoryCheck]:
    """:class:`TrajectoryCheck` of every trajectory in the robot's sidecar, in order."""
    from .inverse_dynamics import InverseDynamics
    from .trajectory import load_trajectory

    specs = robot.sidecar.trajectories if robot.sidecar is not None else {}
    cases = [1] + ([3] if any(j.cone_deg is not None for j in robot.joints) else [])
    solvers = {}
    out = []
    for name in specs:
        try:
            traj = load_trajectory(robot, name)
        except McdmError as exc:
            out.append(TrajectoryCheck(name, error=str(exc)))
            continue
        n = len(traj)
        idx = np.unique(np.linspace(0, n - 1, min(samples, n)).round().astype(int))
        check = TrajectoryCheck(name, instants=n, duration=float(traj.t[-1] - traj.t[0]), checked=idx)
        for case in cases:
            if case not in solvers:
                solvers[case] = InverseDynamics.for_case(robot, case)
            bad = []
            for k in idx:
                try:
                    res = solvers[case].solve(traj.q[k], traj.qd[k], traj.qdd[k])
                except McdmError as exc:
                    bad.append((float(traj.t[k]), "error", str(exc)))
                    continue
                if not res.found:
                    bad.append((float(traj.t[k]), res.status, res.message))
            check.failures[case] = bad
        out.append(check)
    return out
