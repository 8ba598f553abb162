"""Dense forces for the replay: the plan at any time, and the inverse-dynamics problem re-solved on it
(``mcdm-pin verify --resolve``)."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..exceptions import ResultsError, TrajectoryError


def planned_state(robot, spec) -> Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The plan of a sidecar trajectory at any time: ``t -> (q, v, a)`` (configuration, velocity,
    acceleration), as :func:`mcdm_pin.trajectory.plan`: quintics exactly (spherical joints about one
    fixed axis), CSV trajectories through the quintic spline that gives their rates."""
    from ..trajectory import plan

    return plan(robot, spec)


def resolved_forces(ident, plan) -> Callable[[float], np.ndarray]:
    """``t -> f``: the inverse-dynamics problem re-solved on the planned state at time ``t``
    (``ident``: an :class:`~mcdm_pin.inverse_dynamics.InverseDynamics`; ``plan``: :func:`planned_state`),
    the actuators' ``tau_act`` appended on robots with actuators (what the replay takes).
    Raises :class:`TrajectoryError` at a time where it has no valid answer."""
    cache: dict[float, np.ndarray] = {}

    def forces(tt):
        key = float(tt)
        if key not in cache:
            res = ident.solve(*plan(key))
            if not res.found:
                raise TrajectoryError(f"re-solving the forces at t = {key:g} s: {res.status} "
                                      f"({res.message})")
            cache[key] = np.concatenate([res.f, np.asarray(res.tau_act, float).reshape(-1)])
        return cache[key]

    return forces


def problem_from_run(robot, result):
    """Rebuild the problem of a run written by ``mcdm-pin solve``, for :func:`resolved_forces`: from
    its ``problem_json`` (:meth:`~mcdm_pin.problem.Problem.from_spec`: any objective and constraints,
    smoothing and cable weights included), or, for files written before that column existed, from
    its ``problem`` string ``case N: minimise ... subject to ...`` and its ``cone_deg`` (the paper's
    cases only).

    Raises :class:`ResultsError` for problems it cannot rebuild exactly."""
    import ast
    import re

    from ..exceptions import ProblemError
    from ..problem import Problem, case_problem

    if str(getattr(result, "problem_json", "") or ""):
        try:
            return Problem.from_spec(robot, str(result.problem_json))
        except ProblemError as exc:
            raise ResultsError(f"cannot rebuild the problem of this run from its problem_json: {exc}") from None

    text = str(result.problem)
    m = re.match(r"^(?:case [123]: )?minimise (.*) subject to (.*)$", text)
    if not m or "Smoothing" in text or "MinCableForceSum" in text:
        raise ResultsError(f"cannot rebuild the problem of this run from {text!r}: only the paper's "
                           f"cases without smoothing can be re-solved")
    objective = m.group(1)
    case = 1 if objective.startswith("MinCableForces") else 3 if "InteractionCone" in m.group(2) else 2
    alpha = beta = None
    if case == 1:
        if objective != "MinCableForces()":
            raise ResultsError(f"cannot rebuild objective {objective!r} (case 1 with cable weights)")
    else:
        mi = re.match(r"^MinInteractions\(alpha=(.*), beta=(.*)\)$", objective)
        if not mi:
            raise ResultsError(f"cannot rebuild objective {objective!r}")
        alpha, beta = (None if g == "sidecar" else ast.literal_eval(g) for g in mi.groups())
    cones = frame = None
    if case == 3:
        cones = {str(j): float(c) for j, c in zip(result.joint_names, result.cone_deg) if np.isfinite(c)}
        fm = re.search(r"frame='(socket|child)'", text)
        frame = fm.group(1) if fm else "socket"
    return case_problem(robot, case, alpha=alpha, beta=beta, cones=cones, frame=frame or "socket")
