"""Every tolerance of the solvers and of the answer check, in one place.

Two kinds, kept apart on purpose:

- **Acceptance** (``EOM_REL``, ``BOUND_ABS``, ``CONE_DEG``, ``KKT_*``): what an answer must meet before
  it is reported ``optimal``. Checked on the *original* (unscaled) problem by
  :func:`mcdm_pin.solvers.check.kkt_check` and the runner, whatever back-end produced the answer.
- **Inner** (``IPM_*``, ``PROXQP_*``, ``CLARABEL_*``, ``ACTIVE_SET_*``): where each back-end stops. They
  are tighter than acceptance so that an answer that converged passes the check.

Relative tolerances are relative to the sizes of the quantities they compare (stated per constant);
absolute ones carry units (N for cable forces; the unit of each variable in general).
"""

from __future__ import annotations

# --------------------------------------------------------------------------------- acceptance
EOM_REL = 1e-8
"""Equation of motion: ``|A x - b|_inf <= EOM_REL * max(|b|_inf, max_i sum_j |A_ij x_j|)``."""

BOUND_ABS = 1e-9
"""Bounds: ``lb - BOUND_ABS <= x <= ub + BOUND_ABS`` (N for cables)."""

BOUND_SNAP_REL = 1e-7
"""A back-end answer missing a bound by at most ``BOUND_SNAP_REL * (1 + |bound|)`` is projected onto
it (then re-checked); a larger miss is a failure of that back-end."""

CONE_DEG = 1e-6
"""Cones: the interaction angle may exceed the cone's half-angle by this much, degrees."""

KKT_DUAL_REL = 1e-6
"""Dual feasibility and stationarity of an answer, relative to the gradient's scale
(``max(|P x|_inf, |c|_inf, |A^T y|_inf)``): an answer whose multipliers are wrong by more is flagged."""

KKT_GAP_REL = 1e-7
"""Complementarity: ``sum |z_i| * distance_i`` relative to ``1 + |objective|``."""

KKT_GRAD_FLOOR = 1e-6
"""For a constant objective (``P = 0`` and ``c = 0``: case 2 with every weight zero) the gradient scale
of the stationarity and complementarity checks is at least this (objective units per variable unit,
on the problem the back-ends solve, whose variables are of order one: :mod:`mcdm_pin.scaling`). Its
gradient is zero and its multipliers are of rounding or solver-tolerance size (~1e-22 to 1e-15;
Clarabel's leave a duality gap ~4e-14 on CASPR's ACROBOT): relative to their own size they are noise,
not a failure. The floor lets a stationarity residual of 1e-12 and a gap of ~1e-13 pass there."""

# ----------------------------------------------------------------------------- uniqueness
UNIQUE_REL = 1e-9
"""The reduced Hessian on the null space of the strongly active constraints is positive definite when
its smallest eigenvalue exceeds ``UNIQUE_REL`` times the Hessian's largest entry; a bound or cone
whose multiplier is below ``UNIQUE_REL`` of the gradient's scale counts as weakly active (free)."""

UNIQUE_PENALTY = 1e3
"""The uniqueness test's shortcut (:mod:`mcdm_pin.solvers.least_norm`): ``H + gamma J^T J`` with
``gamma`` this times the Hessian's largest entry over ``J^T J``'s. Large enough that a direction the
active rows see is charged far more than ``UNIQUE_REL`` (the shortcut then decides the usual case),
small enough that the Cholesky factor's rounding (~``n 1e-16 UNIQUE_PENALTY`` of the Hessian's
scale) stays far below ``UNIQUE_REL``."""

# ------------------------------------------------------------------------ compiled solvers
ACTIVE_SET_PRIMAL = 1e-12
"""Active-set verification: bounds within ``tol * (1 + |bound|)``."""
ACTIVE_SET_DUAL = 1e-9
"""Active-set verification: multipliers of fixed bounds ``>= -tol * gradient scale``."""
ACTIVE_SET_EOM = 1e-11
"""Active-set verification: equation of motion, relative."""
ACTIVE_SET_REG = 1e-12
"""Tikhonov term on the free variables of an active-set solve, relative to each variable's own
curvature (its diagonal entry of the Hessian; :func:`mcdm_pin.solvers._kkt.tikhonov`)."""
ACTIVE_SET_STEP = 1e-10
"""Newton steps on the cone surfaces: stop when the step is below this, relative."""
ACTIVE_SET_FROM_SOLUTION = 1e-8
"""A variable within this (relative) of a bound counts as at the bound when an active set is read
off another back-end's answer."""

IPM_EPS = 1e-10
"""Interior-point method: relative primal and dual residuals and relative duality gap at the end."""
IPM_CROSSOVER_GAP = 1e-3
"""Interior-point method: from this relative duality gap on, the active set read off the iterate is
tried (verified KKT point) before more iterations. (1e-4 until a wrong guess became cheap: at most
``IPM_CROSSOVER_PIVOTS`` pivots, no SVD; on the neck's ``roll``, cold, 1e-3 saves 0.3-0.9 iterations,
7 us of case 2's 284 us kernel median; ``docs/speed.md``, "Fifth pass".)"""
IPM_MAX_ITER = 60
"""Interior-point method: iteration limit."""
IPM_CORRECTORS = 1
"""Interior-point method: at most this many centrality correctors (Gondzio) per iteration."""
IPM_RANK_TOL = 1e-9
"""Interior-point method: a row of the objective's factor or of a cone whose part outside the span of
the rows before it is below this (relative) counts as dependent."""
IPM_CROSSOVER_PIVOTS = 4
"""Interior-point method: pivots of each crossover attempt before the iterations go on (a right guess
needs one KKT solve; on the neck's ``roll``, cold, a limit of 30 let one attempt take 17 solves, ~250
us, where one more iteration costs ~27 us: case 2's slowest instant 674 -> 454 us, medians unchanged;
``docs/speed.md``, "Fifth pass")."""
IPM_START_BOX_WEIGHT = 0.2
"""Interior-point method: the weight of the bounds in the start's least-squares problem when there
is no cone (CVXOPT's start weighs them 1; :mod:`mcdm_pin.solvers._ipm`, "The start")."""

# -------------------------------------------------------------------------------- ProxQP
PROXQP_EPS_ABS = 1e-11
PROXQP_EPS_REL = 1e-12
"""ProxQP's absolute and relative tolerances on the primal and dual residuals. The relative part
matters when forces reach hundreds of newtons: the dual residual then has a rounding floor near
1e-10 that eps_abs = 1e-11 alone never meets."""
PROXQP_EPS_INFEASIBLE = 1e-7
"""ProxQP's primal/dual infeasibility tolerances (first attempt)."""
CUT_CONE_DEG = 1e-7
"""Cutting planes: largest accepted cone violation, degrees."""
SQP_STEP = 1e-9
"""SQP polish: stop when the step is below this, relative."""
SAME_CUT_COS = 1.0 - 1e-5
"""Cut rows (in x) more parallel than this are merged (the switch to SQP polish)."""

# ------------------------------------------------------------------------------ Clarabel
CLARABEL_TOL = 1e-11
"""Clarabel's gap and feasibility tolerances (``tol_gap_abs``, ``tol_gap_rel``, ``tol_feas``)."""
CLARABEL_KTRATIO = 1e-8

# ------------------------------------------------------------------------------- margins
MARGIN_REL = 1e-9
"""Dinkelbach iterations of :func:`mcdm_pin.solvers.margins.needed_cone_deg` stop when the ratio moves
by less than this, relative."""

# -------------------------------------------------------------------------------- budget
BUDGET_S = 1.0
"""Default per-instant time budget, seconds: a solve that has not answered by then stops between two
stages (or two ProxQP rounds) with status ``budget``."""
