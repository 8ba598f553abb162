"""The two margins of a pose, in one place (the only module of the workspace that knows how they are
computed).

``needed_f_max(qp)``
    The smallest common upper bound ``t`` on the cable forces with which the equation of motion can
    be met: ``min t`` s.t. ``A f = b``, ``f_min <= f <= t`` (an LP). The cones are not part of it. A
    pose is wrench-feasible when ``needed_f_max <= f_max`` (for equal bounds on every cable); ``inf``
    when no bound suffices (some cable would have to push). Newtons.

``needed_cone_deg(qp, solver)`` (case 3)
    The smallest cone half-angle with which the pose is feasible, the cones of all joints moved by one
    common angle (equal cones, e.g. ``--cone all=15``: the smallest common half-angle), reported as the
    largest cone after the move. Below the problem's cone the pose is feasible with margin; above it,
    that is how far the cones must open. ``inf`` when no cone below 90 deg will do. Degrees, to
    ``CONE_TOL_DEG``, and resolved down to ``CONE_FLOOR_DEG``: a pose that the smallest cone holds at
    that angle reports about ``CONE_FLOOR_DEG`` (read: that angle or less). Below it the cone solves
    of today's solver stall (2-link arm: 0.3 deg 30 iterations, 0.1 deg 9582, 0.003 deg 308892 and
    1 s) and answer wrongly (0.001 deg: "infeasible" at a pose feasible at 0.003 deg).

Both are for now thin adapters over the solver's own diagnosis (``inverse_dynamics``:
``_smallest_common_fmax`` and ``_smallest_angle``, a bisection of ~17 cold solves); the solver
stream's fast ``mcdm_pin.solvers.margins`` replaces them here, and nowhere else.
"""

from __future__ import annotations

import numpy as np

from ..constraints import ConeData
from ..inverse_dynamics import _smallest_angle, _smallest_common_fmax

CONE_TOL_DEG = 1e-3  # bisection tolerance of needed_cone_deg, degrees
CONE_FLOOR_DEG = 0.5  # the smallest cone angle the bisection tries, degrees (module docstring)


def needed_f_max(qp) -> float:
    """The smallest common f_max that makes the pose wrench-feasible, N (see the module docstring)."""
    return float(_smallest_common_fmax(qp))


def needed_cone_deg(qp, solver) -> float:
    """The smallest cone half-angle that makes the pose feasible, degrees (module docstring); NaN
    without cones."""
    if not qp.cones:
        return float("nan")
    # the bisection widens every cone by a common angle from where it starts: start it with the
    # smallest cone at the floor, so that it finds the smallest feasible angle on either side of the
    # problem's own cone
    low = min(c.angle_deg for c in qp.cones) - CONE_FLOOR_DEG
    closed = [ConeData(c.joint, c.G, c.g, c.axis, c.angle_deg - low, c.basis) for c in qp.cones]
    return float(_smallest_angle(qp.with_cones(closed), solver, tol_deg=CONE_TOL_DEG))


def pose_margins(qp, solver, cones: bool) -> tuple[float, float]:
    """``(needed_f_max, needed_cone_deg)`` of one assembled pose (the second NaN when ``cones`` is
    false). A pose that no f_max makes wrench-feasible needs no cone search: no cone will do."""
    f_need = needed_f_max(qp)
    if not cones:
        return f_need, float("nan")
    if not np.isfinite(f_need) or f_need > float(np.max(qp.ub)):
        return f_need, float("inf")
    return f_need, needed_cone_deg(qp, solver)
