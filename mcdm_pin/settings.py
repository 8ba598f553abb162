"""Every tolerance, pivot limit and budget of the solvers and of the answer check: one
:class:`Settings` object, passed down from :class:`~mcdm_pin.inverse_dynamics.InverseDynamics` (or
:func:`~mcdm_pin.solvers.make_solver`) to each stage of the chain, to the answer check and to the
compiled kernels, which take the values they need as arguments.

A bottom module (it imports nothing of the package but its exceptions) and a frozen dataclass
rather than module constants: a value read at run time from the object a solver was built with can
differ between two solvers in one process, is seen by the compiled kernels without a recompile,
and cannot be changed behind a running solver's back. :data:`DEFAULT` holds the values the library
uses unless told otherwise; :meth:`Settings.replace` makes a changed copy.

Two kinds of tolerance, kept apart on purpose:

- **Acceptance** (``eom_rel``, ``bound_abs``, ``cone_deg``, ``kkt_*``): what an answer must meet before
  it is reported ``optimal``, whatever back-end produced it. The chain's last stage
  (:func:`mcdm_pin.solvers.check.kkt_problems`: every KKT condition) checks it on the problem the
  back-ends solve, scaled to magnitudes of order one (:mod:`mcdm_pin.scaling`); the runner checks
  the equation of motion, the bounds and the cones again on the *original* problem.
- **Inner** (``ipm_*``, ``proxqp_*``, ``clarabel_*``, ``active_set_*``): where each back-end stops. They
  are tighter than acceptance so that an answer that converged passes the check.

Relative tolerances are relative to the sizes of the quantities they compare (stated per field);
absolute ones carry units (N for cable forces; the unit of each variable in general).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from .exceptions import SolverError


@dataclass(frozen=True)
class Settings:
    """The solvers' and the answer check's tolerances, pivot limits and budget (module docstring).
    Every field has the library's value as its default; each is documented where it is defined
    (``mcdm_pin/settings.py``) and in docs/api/mcdm_pin.settings.md. Invalid values raise
    :class:`~mcdm_pin.exceptions.SolverError` naming the field."""

    # ----------------------------------------------------------------------------- acceptance
    eom_rel: float = 1e-8
    """Equation of motion: ``|A x - b|_inf <= eom_rel * max(|b|_inf, max_i sum_j |A_ij x_j|)``."""
    bound_abs: float = 1e-9
    """Bounds: ``lb - bound_abs <= x <= ub + bound_abs`` (N for cables)."""
    bound_snap_rel: float = 1e-7
    """A back-end answer missing a bound by at most ``bound_snap_rel * (1 + |bound|)`` is projected onto
    it (then re-checked); a larger miss is a failure of that back-end."""
    cone_deg: float = 1e-6
    """Cones: the interaction angle may exceed the cone's half-angle by this much, degrees."""
    kkt_dual_rel: float = 1e-6
    """Dual feasibility and stationarity of an answer, relative to the gradient's scale
    (``max(|P x|_inf, |c|_inf, |A^T y|_inf)``): an answer whose multipliers are wrong by more is flagged."""
    kkt_gap_rel: float = 1e-7
    """Complementarity: ``sum |z_i| * distance_i`` relative to ``1 + |objective|``."""
    kkt_grad_floor: float = 1e-6
    """For a constant objective (``P = 0`` and ``c = 0``: case 2 with every weight zero) the gradient scale
    of the stationarity and complementarity checks is at least this (objective units per variable unit,
    on the problem the back-ends solve, whose variables are of order one: :mod:`mcdm_pin.scaling`). Its
    gradient is zero and its multipliers are of rounding or solver-tolerance size (~1e-22 to 1e-15;
    Clarabel's leave a duality gap ~4e-14 on CASPR's ACROBOT): relative to their own size they are noise,
    not a failure. The floor lets a stationarity residual of 1e-12 and a gap of ~1e-13 pass there."""

    # ---------------------------------------------------------------------------- uniqueness
    unique_rel: float = 1e-9
    """The reduced Hessian on the null space of the strongly active constraints is positive definite when
    its smallest eigenvalue exceeds ``unique_rel`` times the Hessian's largest entry; a bound or cone
    whose multiplier is below ``unique_rel`` of the gradient's scale counts as weakly active (free)."""
    unique_penalty: float = 1e3
    """The uniqueness test's shortcut (:mod:`mcdm_pin.solvers.least_norm`): ``H + gamma J^T J`` with
    ``gamma`` this times the Hessian's largest entry over ``J^T J``'s. Large enough that a direction the
    active rows see is charged far more than ``unique_rel`` (the shortcut then decides the usual case),
    small enough that the Cholesky factor's rounding (~``n 1e-16 unique_penalty`` of the Hessian's
    scale) stays far below ``unique_rel``."""

    # -------------------------------------------------------------------- compiled active set
    active_set_primal: float = 1e-12
    """Active-set verification: bounds within ``tol * (1 + |bound|)``."""
    active_set_dual: float = 1e-9
    """Active-set verification: multipliers of fixed bounds ``>= -tol * gradient scale``."""
    active_set_eom: float = 1e-11
    """Active-set verification: equation of motion, relative."""
    active_set_reg: float = 1e-12
    """Tikhonov term on the free variables of an active-set solve, relative to each variable's own
    curvature (its diagonal entry of the Hessian; :func:`mcdm_pin.solvers._kkt.tikhonov`)."""
    active_set_step: float = 1e-10
    """Newton steps on the cone surfaces: stop when the step, or the next one as their quadratic rate
    predicts it, is below this, relative (:func:`mcdm_pin.solvers._kkt_eq._settled`)."""
    active_set_stationary: float = 1e-8
    """Active-set verification: a free variable's entry of the Lagrangian's gradient (its stationarity
    residual) within this of the gradient's scale (``max(|H f|_inf, |c|_inf, |A^T y|_inf)``)."""
    active_set_surface: float = 1e-10
    """Active-set verification: a held cone's force on its surface,
    ``| |F_perp| - tan(rho) a.F | <= tol |F|``; off it, the Newton steps on the surfaces have not settled and
    the point is not accepted."""
    active_set_settle: float = 1e-12
    """Newton steps on the held cones' surfaces: the prediction that the next step would be below
    ``active_set_step`` ends them only with every held cone's force on its surface to this of ``|F|``
    (:func:`mcdm_pin.solvers._kkt_eq._settled`); short of it, one more step puts the force on the
    surface to rounding. Tighter than the acceptance (``active_set_surface``), so that the chains'
    answers meet the surface alike, not only within what the check accepts (docs/glenohumeral.md
    gives the default chain's forces and Clarabel's on MyoSuite's arm with either tolerance)."""
    active_set_cone: float = 1e-12
    """Active-set verification: a cone not held is broken (it joins the active set) when
    ``|F_perp| > tan(rho) a.F (1 + tol)``."""
    active_set_keep: float = 1e-12
    """The next instant's guess of the bounds from an answer: a variable whose bound's multiplier is
    below this of the largest multiplier is guessed free."""
    active_set_from_solution: float = 1e-8
    """A variable within this (relative) of a bound counts as at the bound when an active set is read
    off another back-end's answer."""
    warm_max_pivots: int = 50
    """The warm active set's pivot limit (block principal pivoting) per instant. A pivot (one active
    set's KKT solve and check) costs a hundredth of a cold solve by the interior-point method or less
    on the neck: at the turning point of the neck's ``roll`` (cases 2 and 3) the active set needs 33 pivots
    (~0.7 ms), and with a limit of 30 that instant costs the pivots *and* the cold solve (~4 ms, the
    trajectory's 99th percentile). 50 pivots keep a warm start that fails under ~1 ms of pivoting."""
    warm_min_pivots: int = 4
    """After a warm start fails, the next instant's pivot limit is half the last one, down to this (at
    most ``warm_max_pivots``); an answer from the warm start restores ``warm_max_pivots``, and so does
    an instant whose answer lies within ``warm_max_pivots`` bound and cone changes of the guess that
    failed (the instants do not jump there). A guess that failed tends to fail again where the
    instants lie far apart, and a pivot's KKT solve grows with the cube of the problem's size: at 96
    DoF and 288 cables, 11 instants over a second, every warm start failed after its 50 pivots and
    took longer than the cold solve that followed (docs/speed.md, "The first stage of a cold
    instant"; "The pivot limit after a failure")."""
    warm_dual_steps: int = 30
    """Where the warm active set's guess fails on a problem whose objective is diagonal and positive
    definite and which has no cones (case 1's ``f^T f``, the muscles' activations), the stage guesses
    again: at most this many Newton steps on the problem's dual from the last answer's multipliers
    (:mod:`mcdm_pin.solvers._dual_guess`), then the active-set solver from the active set they reach
    (``warm_min_pivots``); 0: no second guess. On the neck's ``roll`` (case 1) the three warm starts
    that fail reach their optimum's active set in 6, 10 and 15 steps (docs/speed.md, "The warm
    start's dual guess")."""
    warm_dual_after: int = 6
    """Where the dual guess applies (``warm_dual_steps``), the warm active set's own guess gets at most
    this many pivots (and ``warm_max_pivots``' halving) before it: of 18,565 warm starts that
    answered the shipped robots' case 1 (their first two trajectories), four needed more than six
    KKT solves (8, 10, 11 and 28), and a guess that fails pivots on to its limit (~1 ms on the neck)."""
    cold_dual_steps: int = 30
    """A cold instant (no previous answer) of such a problem starts from the dual guess too, from zero
    multipliers, with at most this many Newton steps (:class:`mcdm_pin.solvers.active_set.DualActiveSet`);
    where the active set they reach does not verify within ``warm_max_pivots`` (no pivot was spent on
    the instant before), the interior-point method answers. 0: every cold instant goes to the
    interior-point method."""
    warm_dual_regularisation: float = 1e-6
    """The dual guess's Newton matrix is ``A_F D_F^-1 A_F^T + r A D^-1 A^T`` with this ``r``: positive
    definite where the free variables do not span the equations (:mod:`mcdm_pin.solvers._dual_guess`)."""
    warm_dual_tol: float = 1e-9
    """The dual guess stops when its active set repeats and ``|A x - b|`` is within this of the
    problem's size (``max(|b|, max |A| max |x|)``), relative."""
    polish_max_pivots: int = 30
    """The polish's pivot limit from another stage's active set."""
    active_set_max_newton: int = 10
    """Newton steps on the cone surfaces per active set tried."""

    # ------------------------------------------------------------------- interior-point method
    ipm_eps: float = 1e-10
    """Interior-point method: relative primal and dual residuals and relative duality gap at the end."""
    ipm_crossover_gap: float = 1e-3
    """Interior-point method: from this relative duality gap on, the active set read off the iterate is
    tried (verified KKT point) before more iterations: a wrong guess costs at most
    ``ipm_crossover_pivots`` pivots, and a right one saves iterations. After the first attempt, an
    active set is tried only once it reads the same at two successive iterations. A pivot solves the
    active set's whole KKT system, so its cost grows with the cube of the problem's size while an
    iteration's grows more slowly: for hundreds of cables a smaller gap (1e-6) answers cold instants
    faster, for tens the default does (docs/speed.md, "The first stage of a cold instant")."""
    ipm_max_iter: int = 60
    """Interior-point method: iteration limit."""
    ipm_correctors: int = 1
    """Interior-point method: at most this many centrality correctors (Gondzio) per iteration."""
    ipm_rank_tol: float = 1e-9
    """Interior-point method: a row of the objective's factor or of a cone whose part outside the span of
    the rows before it is below this (relative) counts as dependent."""
    ipm_crossover_pivots: int = 4
    """Interior-point method: pivots of each crossover attempt before the iterations go on (a right guess
    needs one KKT solve; a long attempt costs more than the iterations it would save: docs/speed.md)."""
    ipm_start_box_weight: float = 0.2
    """Interior-point method: the weight of the bounds in the start's least-squares problem when there
    is no cone (CVXOPT's start weighs them 1; :mod:`mcdm_pin.solvers._ipm`, "The start")."""
    ipm_crossover_attempts: int = 8
    """Interior-point method: at most this many crossover attempts before the iteration limit (each
    costs up to ``ipm_crossover_pivots`` pivots; after the first, only an active set that reads the same
    at two successive iterations is tried)."""
    ipm_pivot_drop: float = 1e-14
    """Interior-point method: a pivot of the Newton system's Cholesky factor below this, relative to its
    diagonal entry's scale, drops that equation as dependent (:mod:`mcdm_pin.solvers._ipm_newton`)."""
    ipm_refine_gap: float = 1e-5
    """Interior-point method: from this relative duality gap on (and after a dropped equation) each
    Newton solve gets a step of iterative refinement."""
    ipm_step_fraction: float = 0.99
    """Interior-point method: the fraction of the step to the boundary of the bounds and cones taken."""
    ipm_min_step: float = 1e-14
    """Interior-point method: a step length below this ends the method (a numerical breakdown: "the
    step vanished")."""
    ipm_certificate: float = 1e-6
    """Interior-point method: an infeasibility certificate ``(y, z)`` counts only when
    ``-(b^T y + h^T z)`` exceeds this times the multipliers' scaled size (not a rounding of zero)."""

    # ---------------------------------------------------------------------------------- ProxQP
    proxqp_eps_abs: float = 1e-11
    """ProxQP's absolute tolerance on the primal and dual residuals."""
    proxqp_eps_rel: float = 1e-12
    """ProxQP's relative tolerance on the primal and dual residuals. It matters when forces reach
    hundreds of newtons: the dual residual then has a rounding floor near 1e-10 that
    ``proxqp_eps_abs = 1e-11`` alone never meets."""
    proxqp_eps_infeasible: float = 1e-7
    """ProxQP's primal/dual infeasibility tolerances (first attempt)."""
    proxqp_max_iter: int = 1000
    """ProxQP's iteration limit (first attempt)."""
    proxqp_max_iter_retry: int = 5000
    """ProxQP's iteration limit when it retries from scratch."""
    cut_cone_deg: float = 1e-7
    """Cutting planes: largest accepted cone violation, degrees."""
    sqp_step: float = 1e-9
    """SQP polish: stop when the step is below this, relative."""
    same_cut_cos: float = 1.0 - 1e-5
    """Cut rows (in x) more parallel than this are merged (the switch to SQP polish)."""

    # -------------------------------------------------------------------------------- Clarabel
    clarabel_tol: float = 1e-11
    """Clarabel's gap and feasibility tolerances (``tol_gap_abs``, ``tol_gap_rel``, ``tol_feas``)."""
    clarabel_ktratio: float = 1e-8
    """Clarabel's ``tol_ktratio``."""
    clarabel_max_iter: int = 200
    """Clarabel's iteration limit."""

    # --------------------------------------------------------------------------------- margins
    margin_rel: float = 1e-9
    """Dinkelbach iterations of :func:`mcdm_pin.solvers.margins.needed_cone_deg` stop when the ratio moves
    by less than this, relative."""

    # ---------------------------------------------------------------------------------- budget
    budget_s: float | None = 1.0
    """Per-instant time budget, seconds (``None``: none): a solve that has not answered by then stops
    between two stages (or two ProxQP rounds) with status ``budget``."""

    def __post_init__(self):
        for f in dataclasses.fields(self):
            _check(f.name, f.default, getattr(self, f.name))

    def replace(self, **changes) -> "Settings":
        """A copy with ``changes`` (field names as keywords); an unknown name or a bad value raises
        :class:`~mcdm_pin.exceptions.SolverError` naming the field and what it expects."""
        known = {f.name for f in dataclasses.fields(self)}
        for name in changes:
            if name not in known:
                raise SolverError(f"unknown setting {name!r}; expected one of {', '.join(sorted(known))}")
        return dataclasses.replace(self, **changes)


def _check(name: str, default, value) -> None:
    """``value`` of the field ``name`` is of its default's kind: a positive int for the limits (zero
    allowed for ``ipm_correctors``, ``warm_dual_steps`` and ``cold_dual_steps``), a positive finite
    float for the tolerances (``same_cut_cos`` and ``ipm_step_fraction`` at most 1), a float >= 0 or
    ``None`` for the budget."""
    if name == "budget_s" and (value is None or (isinstance(value, (int, float)) and not isinstance(value, bool)
                                                 and value == 0)):
        return  # (a zero budget: no answering stage after the first starts)
    if isinstance(default, int) and not isinstance(default, bool):
        least = 0 if name in ("ipm_correctors", "warm_dual_steps", "cold_dual_steps") else 1
        if isinstance(value, bool) or not isinstance(value, int) or value < least:
            raise SolverError(f"setting {name!r} must be an integer >= {least}, got {value!r}")
        return
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0
    if not ok or (name in _AT_MOST_ONE and value > 1.0):
        what = "a float in (0, 1]" if name in _AT_MOST_ONE else "a positive finite number"
        what = "a number >= 0 or None" if name == "budget_s" else what
        raise SolverError(f"setting {name!r} must be {what}, got {value!r}")


_AT_MOST_ONE = ("same_cut_cos", "ipm_step_fraction")  # fractions: in (0, 1]
DEFAULT = Settings()
"""The library's settings (every field at its default)."""

__all__ = ["Settings", "DEFAULT"]
