"""The verdict on a convergence table: *converged*, *diverged* or *not converged*, and what to do.

Rules (rad or m; ``S`` is the motion's range over the replayed stretch, at least ``MIN_RANGE``):

* **diverged**: the finest replay's state stops being finite, or it ends farther from the plan than
  ``DIVERGED_FRACTION * S``. The integrator may converge perfectly (its self error falling at its
  order) while the replay diverges: an open-loop unstable robot amplifies any small difference
  (interpolation of the forces, rounding) by ``exp(growth_rate * T)``. Then a *window* is searched:
  the largest number of sample intervals ``W`` after which restarting from the plan keeps the replay
  on it, starting from ``1 / (growth_rate * dt)`` (amplification ``e`` per window) and halving.
* **not converged**: the integrator's self error does not fall at its order (``ORDER_TOL``), unless it
  is already at rounding level (``ROUND_OFF * max(S, 1)``); with ``--resolve``, the plan error itself
  must fall at the integrator's order (or be at the solver's accuracy, ``SOLVER_FLOOR``).
* **converged** otherwise: the forces reproduce the plan to the finest replay's error.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .replay import ConvergenceTable, ReplayReport, replay

DIVERGED_FRACTION = 0.1
MIN_RANGE = 1e-2
ORDER_TOL = 0.6
ROUND_OFF = 1e-10
SOLVER_FLOOR = 1e-8
FLAT = 0.1  # plan errors of the last two levels within 10 %: a floor that does not move with the step


@dataclass
class Verdict:
    """What :func:`judge` concluded.

    Attributes:
        status: ``converged``, ``diverged`` or ``not converged``.
        reasons: sentences that explain it, with the numbers.
        window: a ``--window`` with which the replay follows the plan (diverged runs), or ``None``.
        window_error: the replay's ``max |q - q_plan|`` with that window.
        substeps: a ``--substeps`` to use instead (not converged), or ``None``.
    """

    status: str
    reasons: list[str] = field(default_factory=list)
    window: int | None = None
    window_error: float = float("nan")
    substeps: int | None = None

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    def text(self) -> str:
        return f"verdict: {self.status}. " + " ".join(self.reasons)


def motion_range(robot, report: ReplayReport) -> float:
    """Largest range (max - min) of any coordinate of the plan over the replay, rad or m (measured
    as ``pin.difference`` from the first planned configuration)."""
    q0 = report.q_plan[0]
    d = np.array([pin.difference(robot.model, q0, q) for q in report.q_plan])
    return float(np.ptp(d, axis=0).max()) if d.size else 0.0


def _is_diverged(report: ReplayReport, scale: float) -> bool:
    return report.diverged_at is not None or not report.max_error <= DIVERGED_FRACTION * scale


def _order_ok(observed: np.ndarray, order: int) -> bool:
    return len(observed) > 0 and bool(np.isfinite(observed[-1])) and abs(observed[-1] - order) <= ORDER_TOL


def judge(robot, result, table: ConvergenceTable, integrator: str = "rk4", substeps: int = 1,
          hold: str = "linear", forces=None, window: int | None = None) -> Verdict:
    """The verdict on ``table`` (from :func:`~mcdm_pin.verify.convergence` with the same options);
    for a diverged replay it runs a few more replays to find a window that works."""
    fine = table.reports[-1]
    S = max(motion_range(robot, fine), MIN_RANGE)
    e = fine.max_error
    p = table.order
    h = fine.step
    se = table.self_error
    self_ok = bool(np.isfinite(se[-1]) and se[-1] <= ROUND_OFF * max(S, 1.0)) or _order_ok(
        table.observed_order, p)
    seen = (f"order {table.observed_order[-1]:.2f}" if len(table.observed_order)
            and np.isfinite(table.observed_order[-1]) else "order not measured")
    rate, T = table.growth_rate, float(fine.t[-1] - fine.t[0])
    unstable = (f"Under force control the robot is open-loop unstable (growth rate {rate:.3g} 1/s at "
                f"t = {table.growth_at:g} s): any small difference from the plan grows like "
                f"exp({rate:.3g} t), by {np.exp(min(rate * T, 700.0)):.2g} over the {T:g} s replayed"
                + (f" ({window} intervals per window)" if window else "") + ".") if rate > 0 else ""
    if _is_diverged(fine, S):
        where = (f"its state stops being finite at t = {fine.diverged_at:g} s" if fine.diverged_at is not None
                 else f"it strays up to {e:.3g} (rad or m) from the plan, {100 * e / S:.0f} % of the "
                      f"motion's range ({S:.3g})")
        reasons = [f"The replay diverges from the plan: at the finest step ({h:.3g} s) {where}."]
        if self_ok and fine.diverged_at is None:
            reasons.append(f"The integrator itself converges ({seen}, expected {p}), so the step is not "
                           f"the cause.")
        if unstable:
            reasons.append(unstable)
        v = Verdict("diverged", reasons)
        _suggest_window(v, robot, result, table, integrator, substeps, hold, forces, window, S)
        return v
    if forces is not None:  # --resolve: the plan is the exact solution
        plan_ok = e <= SOLVER_FLOOR * max(S, 1.0) or _order_ok(table.plan_order, p)
        po = table.plan_order[-1] if len(table.plan_order) else np.nan
        if plan_ok:
            return Verdict("converged", [
                f"With the forces re-solved on the plan, max |q - q_plan| falls at order {po:.2f} "
                f"(expected {p}) to {e:.3g} at the finest step: the forces produce the planned motion."])
        return Verdict("not converged", [
            f"With the forces re-solved on the plan, max |q - q_plan| should fall at order {p}, but "
            f"falls at {po:.2f} (to {e:.3g}): where the optimal set of active cables changes, f(t) has "
            f"a kink that costs the integrator its order; more --levels show whether it recovers."])
    if not self_ok:
        v = Verdict("not converged", [f"The integrator's own error (max |q_h - q_h/2|) does not fall at "
                                      f"its order {p} ({seen}; {se[-1]:.3g} at the finest step)."])
        if rate > 0 and rate * h > 0.5:
            v.substeps = int(2 ** np.ceil(np.log2(max(1.0, rate * h * substeps * 2 ** (len(table.reports) - 1)
                                                       / 0.5))))
            v.reasons.append(f"The step times the growth rate ({rate * h:.2g}) is too large for the "
                             f"integrator: try --substeps {v.substeps}.")
        elif not len(table.observed_order):
            v.reasons.append("Two levels give one self error and no order: use --levels 3 or more.")
        else:
            v.reasons.append("Add --levels to halve the step further.")
        return v
    floor = ("" if len(table.reports) < 2 or abs(table.plan_error[-2] - e) > FLAT * e else
             f" That error does not move with the step: it is the floor set by interpolating f between "
             f"the instants ({'O(dt^2)' if hold == 'linear' else 'O(dt)'} in their spacing), not the "
             f"integrator's.")
    return Verdict("converged", [
        f"The integrator converges ({seen}, expected {p}; max |q_h - q_h/2| = {se[-1]:.3g} at the "
        f"finest step) and the replay follows the plan to {e:.3g} rad or m ({100 * e / S:.2g} % of the "
        f"motion's range, {S:.3g}).{floor}"])


def _suggest_window(v: Verdict, robot, result, table, integrator, substeps, hold, forces, window,
                    scale) -> None:
    """Find the largest window (sample intervals) with which the replay stays on the plan."""
    fine = table.reports[-1]
    dt = float(np.median(np.diff(fine.t)))
    rate = table.growth_rate
    if window is not None:
        start = max(1, window // 2)
    elif rate > 0:
        start = max(1, int(1.0 / (rate * dt)))
    else:
        start = max(1, (len(fine.t) - 1) // 4)
    # keep the step inside RK4's stability region: rate * h <= 1
    steps = max(substeps, int(np.ceil(rate * dt))) if rate > 0 else substeps
    w = start
    while True:
        rep = replay(robot, result, integrator, steps, hold, forces, w)
        if not _is_diverged(rep, scale):
            v.window, v.window_error = w, rep.max_error
            v.reasons.append(f"Restarting from the plan every {w} instant(s) keeps the replay on it: "
                             f"--window {w}" + (f" --substeps {steps}" if steps != substeps else "")
                             + f" gives max |q - q_plan| = {rep.max_error:.3g}.")
            return
        if w == 1:
            v.reasons.append("Even restarting from the plan at every instant the replay leaves it: the "
                             "forces do not produce the motion (check the run's status and messages).")
            return
        w = max(1, w // 2)
