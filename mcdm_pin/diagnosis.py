"""What cannot be met at an infeasible instant, and what would make it feasible.

:func:`diagnose_infeasible` says whether the cable bounds or the cones cannot be met, and the f_max or
cone angle that would do (:mod:`mcdm_pin.solvers.margins`); :func:`soften_cones` solves the instant
with every cone widened to the smallest common half-angle that makes it feasible (status
``softened``). :class:`~mcdm_pin.inverse_dynamics.InverseDynamics` calls both on infeasible instants.
"""

from __future__ import annotations

import numpy as np

from .model.actuators import actuator_names
from .qp import QPData
from .settings import DEFAULT, Settings
from .solvers import INFEASIBLE, OPTIMAL, SOFTENED, Solution
from .solvers.clarabel_ import clarabel_solve
from .solvers.margins import needed_cone_deg, needed_f_max


def diagnose_infeasible(qp: QPData, cable_names=None, settings: Settings = DEFAULT):
    """What cannot be met at an infeasible instant, and what would make it feasible (the cone programs'
    tolerances: ``settings``).

    Returns ``(message, needed_f_max, needed_cone_deg)``:

    - bounds alone (equation of motion within the bounds, an LP decided by HiGHS): the message names
      the cables whose bounds must give (an elastic LP: the least total violation) and
      ``needed_f_max`` is the smallest common upper bound that would do
      (:func:`~mcdm_pin.solvers.margins.needed_f_max`; ``inf``: none would, the cables would have to
      push);
    - the cones: ``needed_cone_deg`` is the smallest common half-angle of all cones that makes the
      instant feasible (:func:`~mcdm_pin.solvers.margins.needed_cone_deg`, a few cone programs), and
      the message names the cones that bind there;
    - neither (the bounds' LP is feasible and there is no cone): the solver's infeasibility was
      false; the message starts with ``solver`` and the caller reports the instant ``inaccurate``.
    """
    names = list(cable_names) if cable_names is not None else [f"cable {i}" for i in range(qp.n)]
    nan = float("nan")
    if _feasible_lp(qp) is None:
        below, above = _elastic_bounds(qp)
        parts = []
        if above:
            parts.append("above f_max: " + ", ".join(names[i] for i in above))
        if below:
            parts.append("below f_min: " + ", ".join(names[i] for i in below))
        need = needed_f_max(qp.without_cones())
        tail = (f"; a common f_max of {need:.6g} N would suffice" if np.isfinite(need) else
                "; no f_max suffices (some cable would have to push)")
        where = f" (the least change needs forces {'; '.join(parts)})" if parts else ""
        return ("bounds: the equation of motion cannot be met with cable forces within "
                f"[f_min, f_max]{where}{tail}", need, nan)
    if not qp.cones:
        return ("solver: reported infeasible, but the equation of motion can be met within the bounds "
                "(a numerical failure of the solver)", nan, nan)
    need = needed_cone_deg(qp, settings=settings)
    if len(qp.cones) == 1:
        cone = qp.cones[0]
        where = (f"feasible from {need:.4f} deg" if need < 90.0 else
                 "only a half-space would do: the force must lie in the socket's plane" if need == 90.0 else
                 "no cone will do: the force must point out of the socket")
        return (f"cone: the stability cone of {cone.joint} ({cone.angle_deg:g} deg; {where}) cannot be met "
                f"within the cable bounds", nan, float(need))
    names_c = ", ".join(f"{c.joint} ({c.angle_deg:g} deg)" for c in qp.cones)
    if not need < 90.0:
        return (f"cones: the stability cones of {names_c} cannot be met together within the cable bounds; "
                f"{'only half-spaces would do' if need == 90.0 else 'no common cone will do: a force must point out of its socket'}",
                nan, float(need))
    binding = _binding_cones(qp, need, settings)
    return (f"cones: the stability cones of {names_c} cannot be met together within the cable bounds; "
            f"a common half-angle of {need:.4f} deg would do (binding there: {', '.join(binding)})",
            nan, float(need))


def _binding_cones(qp: QPData, angle_deg: float, settings: Settings) -> list[str]:
    """The cones at their limit when every cone is at ``angle_deg`` (solved by Clarabel)."""
    if not np.isfinite(angle_deg) or angle_deg >= 90.0:
        return [c.joint for c in qp.cones]
    wide = qp.with_cones([c.with_angle(max(c.angle_deg, angle_deg) + 1e-6) for c in qp.cones])
    sol = clarabel_solve(wide, settings)
    if sol.status != OPTIMAL:
        return [c.joint for c in qp.cones]
    return [c.joint for c in wide.cones if c.angle_of(sol.x) >= angle_deg - 1e-3]


def _feasible_lp(qp: QPData):
    # here, not at import: only an infeasible instant needs it, and every command's start would pay for it
    from scipy.optimize import linprog

    res = linprog(np.zeros(qp.n), A_eq=qp.A if len(qp.b) else None, b_eq=qp.b if len(qp.b) else None,
                  bounds=list(zip(qp.lb, qp.ub)), method="highs")
    return res.x if res.status == 0 else None


def _elastic_bounds(qp: QPData, rel: float = 1e-9):
    """Cables whose bounds must give, by the least total violation (relative to each bound). An
    infinite bound (an unbounded motor's) has no slack: it cannot be broken."""
    n = qp.n
    lo_i, hi_i = np.flatnonzero(np.isfinite(qp.lb)), np.flatnonzero(np.isfinite(qp.ub))
    k_lo, k_hi = len(lo_i), len(hi_i)
    lb, ub = qp.lb[lo_i], qp.ub[hi_i]
    c = np.concatenate([np.zeros(n), 1.0 / (1.0 + np.abs(lb)), 1.0 / (1.0 + np.abs(ub))])
    A_ub = np.zeros((k_lo + k_hi, n + k_lo + k_hi))
    A_ub[np.arange(k_lo), lo_i] = -1.0  # -x - s_lo <= -lb
    A_ub[np.arange(k_lo), n + np.arange(k_lo)] = -1.0
    A_ub[k_lo + np.arange(k_hi), hi_i] = 1.0  # x - s_hi <= ub
    A_ub[k_lo + np.arange(k_hi), n + k_lo + np.arange(k_hi)] = -1.0
    A_eq = np.hstack([qp.A, np.zeros((len(qp.b), k_lo + k_hi))])
    from scipy.optimize import linprog

    res = linprog(c, A_ub=A_ub if k_lo + k_hi else None, b_ub=np.concatenate([-lb, ub]) if k_lo + k_hi else None,
                  A_eq=A_eq, b_eq=qp.b, bounds=[(None, None)] * n + [(0, None)] * (k_lo + k_hi), method="highs")
    if res.status != 0:
        return [], []
    s_lo, s_hi = res.x[n:n + k_lo], res.x[n + k_lo:]
    return (lo_i[s_lo > rel * (1.0 + np.abs(lb))].tolist(), hi_i[s_hi > rel * (1.0 + np.abs(ub))].tolist())


def soften_cones(qp: QPData, solver, needed: float | None = None,
                 settings: Settings = DEFAULT) -> tuple[Solution, float]:
    """Every cone at least at the smallest common half-angle that makes the instant feasible
    (``needed``: that angle when known, else found to ``settings``' tolerances), solved there. Returns the solution (status ``softened``)
    and the largest widening, degrees."""
    need = needed_cone_deg(qp, settings=settings) if needed is None or not np.isfinite(needed) else needed
    if not np.isfinite(need) or need >= 90.0:
        return Solution(np.full(qp.n, np.nan), INFEASIBLE, float("nan"),
                        message="no force presses the balls into their sockets at all"), 0.0
    # a hair above the limit: at exactly the limit the feasible set is a single point
    angle = min(need + 1e-7, 89.999999)
    cones = [c.with_angle(max(c.angle_deg, angle)) for c in qp.cones]
    sol = solver.fresh().solve(qp.with_cones(cones))
    widening = max(c.angle_deg - c0.angle_deg for c, c0 in zip(cones, qp.cones))
    if sol.status != OPTIMAL:
        return sol, widening
    return sol.but(status=SOFTENED), widening


def variable_names(robot) -> list[str]:
    """The unknowns' names: the cables, then the actuator components (hybrid robots)."""
    return list(robot.cable_names) + actuator_names(robot)


__all__ = ["diagnose_infeasible", "soften_cones", "variable_names"]
