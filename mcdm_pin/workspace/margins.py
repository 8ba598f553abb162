"""The two margins of a pose, in one place (the only module of the workspace that knows how they are
computed): thin adapters over the solver's margins (:mod:`mcdm_pin.solvers.margins`).

``needed_f_max(qp)``
    The smallest common upper bound ``t`` on the cable forces with which the equation of motion can
    be met: ``min t`` s.t. ``A f = b``, ``f_min <= f <= t`` (one LP). The cones are not part of it: a
    pose is *wrench-feasible* when ``needed_f_max <= f_max`` (for equal bounds on every cable); ``inf``
    when no bound suffices (some cable would have to push). Newtons.

``needed_cone_deg(qp)`` (case 3)
    The smallest common cone half-angle (every cone of the problem at that one angle) with which the
    pose is feasible, the bounds kept: a generalized fractional program solved by a Dinkelbach-type
    method in 3-6 cone programs (:func:`mcdm_pin.solvers.margins.needed_cone_deg`). At or below the
    problem's cone the pose is feasible with that margin; above it, that is how far the cones must open.
    ``90`` when only a half-space would do, ``inf`` when not even that. Degrees, to ``CONE_TOL_DEG``.
    For the usual equal cones (``--cone all=15``) it is the margin of each; with unequal cones it is
    the one angle that would serve them all.
"""

from __future__ import annotations

import numpy as np

from ..solvers import margins as _margins

CONE_TOL_DEG = 1e-3  # accuracy of needed_cone_deg, degrees (its iteration stops far below: MARGIN_REL)


def needed_f_max(qp) -> float:
    """The smallest common f_max that makes the pose wrench-feasible, N (see the module docstring)."""
    return float(_margins.needed_f_max(qp.with_cones([]) if qp.cones else qp))


def needed_cone_deg(qp, solver=None) -> float:
    """The smallest common cone half-angle that makes the pose feasible, degrees (module docstring);
    NaN without cones. ``solver`` is not used (kept for callers of the earlier bisection)."""
    if not qp.cones:
        return float("nan")
    return float(_margins.needed_cone_deg(qp))


def pose_margins(qp, solver, cones: bool) -> tuple[float, float]:
    """``(needed_f_max, needed_cone_deg)`` of one assembled pose (the second NaN when ``cones`` is
    false). A pose that no f_max makes wrench-feasible needs no cone search: no cone will do."""
    f_need = needed_f_max(qp)
    if not cones:
        return f_need, float("nan")
    if not np.isfinite(f_need) or f_need > float(np.max(qp.ub)):
        return f_need, float("inf")
    return f_need, needed_cone_deg(qp)
