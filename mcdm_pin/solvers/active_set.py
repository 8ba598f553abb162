r"""Active-set stages: try a guessed active set, accept only a verified KKT point.

Along a trajectory the set of variables at a bound and of cones that bind changes rarely. Given such a
guess — variables fixed at their lower (``1``) or upper (``2``) bound, cones held on their surface —
the optimum for that active set solves an equality-constrained problem: one linear KKT system for the
bounds, a few Newton (SQP) steps for the cones (each cone's surface
:math:`c_k(x) = \|F_\perp\| - \tan\rho^*_k\, a^T F = 0` linearised, its curvature weighted by its
multiplier). The point is returned only if it satisfies *all* the KKT conditions of the full convex
problem to tight tolerances (:class:`mcdm_pin.settings.Settings`, ``active_set_*``):

- primal: equation of motion, every bound, every inactive cone (within its angle), active cones on
  the right nappe (``a . F > 0``);
- dual: multipliers of the fixed bounds and active cones have the right sign;
- stationarity on the free variables (by construction, checked).

For a convex problem these conditions are sufficient: a verified point is a global optimum. When a
check fails, block principal pivoting corrects the guess (compiled: :func:`._kkt.active_set_run`);
when it cannot, the stage has nothing to say and the next stage answers.

Three stages use it: :class:`WarmActiveSet` (the previous instant's active set), :class:`DualActiveSet`
(a cold instant's: the active set read off the dual's optimum, where the objective is diagonal) and
:class:`Polish` (the active set of another stage's answer: its exact KKT point, to rounding instead
of to that stage's tolerance).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import jit
from ..qp import QPData
from ..settings import DEFAULT, Settings
from . import _dual_guess, _fast
from . import _kkt as K
from ._structs import QP, Cones, Limits
from .base import OPTIMAL, Solution, Stage


def kernel_qp(qp: QPData, factor: tuple | None = None) -> QP:
    """``qp`` as the compiled solvers take it (:class:`._structs.QP`: C-ordered float arrays, made
    once per problem by :meth:`QPData.kernel_arrays`, and Python scalars, so that one compiled
    specialisation serves every call). ``factor``: ``(d0, F)`` with ``P = diag(d0) + F^T F`` for the
    interior-point method (:func:`.ipm.p_structure`); empty where only the active-set solver runs,
    and then made once per problem (the least-norm stage reads the first stage's again).
    ``strict``: :meth:`QPData.strictly_convex` (:func:`.least_norm.is_unique`'s first test)."""
    if factor is None and qp._kernel_qp is not None:
        return qp._kernel_qp
    c_ = np.ascontiguousarray
    c, A, b, lb, ub = qp.kernel_arrays()[:5]
    d0, F = (_EMPTY_F, np.zeros((0, qp.n))) if factor is None else (c_(factor[0], dtype=float),
                                                                       c_(factor[1], dtype=float))
    out = QP(c_(qp.P, dtype=float), d0, F, c, float(qp.r), A, b, lb, ub, qp.strictly_convex())
    if factor is None:
        qp._kernel_qp = out
    return out


def kernel_cones(qp: QPData) -> Cones:
    """``qp``'s cones as the compiled solvers take them (:class:`._structs.Cones`, from
    :meth:`QPData.kernel_arrays` and :meth:`QPData.cone_consts`, both made once per problem)."""
    G, gc, ax, tn, basis0 = qp.kernel_arrays()[5:]
    _, _, cosr, basis = qp.cone_consts()
    return Cones(G, gc, ax, tn, basis0, cosr, basis)


def kernel_limits(settings: Settings, max_pivots: int) -> Limits:
    """The compiled solvers' limits and tolerances (:class:`._structs.Limits`) from ``settings``, with
    the active-set solver's pivot limit ``max_pivots`` (the warm start's, the polish's or each
    crossover's); made once per settings object and limit (settings are immutable)."""
    key = (id(settings), max_pivots)
    hit = _LIMITS.get(key)
    if hit is not None and hit[0] is settings:
        return hit[1]
    if len(_LIMITS) > 256:  # (many settings objects, as a sweep over them makes: start again)
        _LIMITS.clear()
    limits = _limits(settings, max_pivots)
    _LIMITS[key] = (settings, limits)
    return limits


_LIMITS: dict = {}  # (id(settings), max_pivots) -> (settings, Limits)


def _limits(settings: Settings, max_pivots: int) -> Limits:
    s = settings
    return Limits(int(max_pivots), int(s.active_set_max_newton), float(s.active_set_step), float(s.active_set_primal),
                  float(s.active_set_dual), float(s.active_set_eom), float(s.active_set_reg),
                  float(s.active_set_stationary), float(s.active_set_surface), float(s.active_set_settle),
                  float(s.active_set_cone), float(s.active_set_keep), float(s.active_set_from_solution), float(s.unique_rel),
                  float(s.unique_penalty), int(s.ipm_max_iter), float(s.ipm_eps), float(s.ipm_crossover_gap),
                  int(s.ipm_correctors), float(s.ipm_rank_tol), float(s.ipm_start_box_weight),
                  int(s.ipm_crossover_attempts), float(s.ipm_pivot_drop), float(s.ipm_refine_gap),
                  float(s.ipm_step_fraction), float(s.ipm_min_step), float(s.ipm_certificate))


@dataclass
class ActiveSet:
    """A guess: index arrays of variables at their lower/upper bound, and per cone joint its surface
    direction (unit vector of F_perp) and multiplier when it binds. ``state``, when given (int8
    codes per variable: 0 free, 1 lower, 2 upper), takes the place of ``lower`` and ``upper``.
    ``held``, when given, is ``cones`` as arrays for the problem's cones named ``names`` (a mask and
    the directions, (K,) and (K, 3)): what the compiled kernel takes, kept from the answer that
    made the guess. ``point``, when given, is that answer's point and its cones' multipliers, from
    which the kernel's first Newton step on the held cones starts (:func:`._kkt_eq.eq_solve`)."""

    lower: np.ndarray
    upper: np.ndarray
    cones: dict = field(default_factory=dict)  # joint -> (direction (3,), multiplier)
    state: np.ndarray | None = None
    held: tuple | None = None  # (names, mask, directions)
    point: tuple | None = None  # (x (n,), multipliers (K,)) of the answer that made the guess

    def cone_guess(self, qp: QPData) -> tuple[np.ndarray, np.ndarray]:
        """``(mask, directions)`` of the held cones over ``qp``'s cones (directions of the others:
        anything, the kernel starts them from ``basis0``)."""
        if self._made_for(qp):
            return self.held[1], self.held[2]
        names = qp.cone_consts()[0]
        if not names:  # (a least-norm problem whose one cone is held: no mask to make)
            return _NO_MASK, _NO_DIRS
        mask = np.array([nm in self.cones for nm in names], dtype=np.bool_)
        dirs = np.zeros((len(names), 3))
        for k in np.flatnonzero(mask):
            dirs[k] = self.cones[names[k]][0]
        return mask, dirs

    def point_guess(self, qp: QPData) -> tuple[np.ndarray, np.ndarray]:
        """``(x0, mus0)`` for the kernel: :attr:`point` where it was made on a problem of ``qp``'s
        variables and cones, else empty (none)."""
        if self.point is None or not self._made_for(qp) or len(self.point[0]) != qp.n:
            return _EMPTY_F, _EMPTY_F
        return self.point

    def _made_for(self, qp: QPData) -> bool:
        """Whether :attr:`held` was made on a problem with ``qp``'s cones (the same names in order)."""
        return self.held is not None and self.held[0] == qp.cone_consts()[0]

    def cable_state(self, n: int) -> np.ndarray:
        if self.state is not None and self.state.shape == (n,):
            return self.state
        state = np.zeros(n, dtype=np.int8)
        state[self.lower] = 1
        state[self.upper] = 2
        return state

    @classmethod
    def from_solution(cls, qp: QPData, x: np.ndarray, cone_mult: dict, bound_mult=None,
                      rel: float = DEFAULT.active_set_from_solution):
        """The active set of a point: variables within ``rel`` (relative) of a bound whose
        multiplier pushes them onto it (``bound_mult``: > 0 at a lower bound, < 0 at an upper bound;
        None: position only), and cones with a positive multiplier whose force is on the surface."""
        near_l = x - qp.lb <= rel * (1.0 + np.abs(qp.lb))
        near_u = qp.ub - x <= rel * (1.0 + np.abs(qp.ub))
        if bound_mult is not None:
            thr = 1e-12 * max(np.abs(bound_mult).max(initial=0.0), 1e-300)
            near_l &= bound_mult > thr
            near_u &= bound_mult < -thr
        cones = {}
        if qp.cones:
            G, gc, ax, tan, _ = qp.cone_arrays()
            F = gc + G @ x
            along = np.einsum("ka,ka->k", ax, F)
            perp = F - along[:, None] * ax
            norm = np.sqrt(np.einsum("ka,ka->k", perp, perp))
            for k, cone in enumerate(qp.cones):
                mult = cone_mult.get(cone.joint, 0.0)
                # binding: a positive multiplier and the force on the cone's surface (a cutting-plane
                # solver reports tiny positive multipliers on cuts of cones that do not bind)
                if mult > 0 and norm[k] > 0 and norm[k] >= tan[k] * along[k] * (1.0 - rel):
                    cones[cone.joint] = (perp[k] / norm[k], mult)
        return cls(np.flatnonzero(near_l), np.flatnonzero(near_u), cones)

    @classmethod
    def from_duals(cls, qp: QPData, sol: Solution, rel: float = DEFAULT.active_set_from_solution) -> "ActiveSet":
        """The active set of an answer with duals (:mod:`.base` convention); position only when it
        has none (``rel``: :meth:`from_solution`'s)."""
        mult = {}
        if qp.cones and sol.z_cone is not None:
            cosr = np.cos(np.radians([c.angle_deg for c in qp.cones]))
            mult = {c.joint: float(sol.z_cone[k, 0] * cosr[k]) for k, c in enumerate(qp.cones)}
        elif qp.cones:
            mult = {c.joint: 1.0 for c in qp.cones}
        return cls.from_solution(qp, sol.x, mult, None if sol.z is None else -sol.z, rel)


def cone_duals(qp: QPData, mus: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    r"""The second-order-cone duals (:meth:`QPData.cone_rows` form) of surface multipliers ``mus``
    with surface directions ``dirs``: :math:`\mu_k/\cos\rho_k\,(1, -d_k\cdot e_1, -d_k\cdot e_2)`."""
    K_ = len(qp.cones)
    out = np.zeros((K_, 3))
    for k in np.flatnonzero(mus):
        c = qp.cones[k]
        out[k, 0] = mus[k] / np.cos(np.radians(c.angle_deg))
        out[k, 1:] = -out[k, 0] * (c.basis @ dirs[k])
    return out


def try_active_set(qp: QPData, guess: ActiveSet, max_pivots: int = 30, stage: str = "",
                   settings: Settings = DEFAULT):
    """The verified optimum reached from ``guess`` (a :class:`~.base.Solution` whose ``active`` is
    the guess for the next instant, and whose ``iterations`` count the linear KKT systems solved: one
    per active set tried, one per Newton step when cones are held), or ``None``.

    Starting from ``guess``, the active set is corrected by block principal pivoting (free variables
    that leave their bounds are fixed there, fixed ones whose multiplier has the wrong sign are
    freed, broken cones join, cones with a negative multiplier leave) for at most ``max_pivots``
    equality-constrained solves; a repeated active set stops it (tolerances and Newton steps:
    ``settings``). One compiled call
    (:func:`._fast.active_set_answer`: the kernel and the answer's duals, what
    :func:`active_solution` computes in numpy)."""
    state = guess.cable_state(qp.n)  # (the kernel frees variables guessed at an infinite bound)
    cact, cdir = guess.cone_guess(qp)
    x0, mus0 = guess.point_guess(qp)
    c_ = np.ascontiguousarray
    out = jit.kernels("solvers._fast").active_set_answer(  # (plain tuples at the boundary: ._structs)
        tuple(kernel_qp(qp)), tuple(kernel_cones(qp)), c_(state, dtype=np.int8), c_(cact, dtype=np.bool_),
        c_(cdir, dtype=float), tuple(kernel_limits(settings, max_pivots)), c_(x0, dtype=float), c_(mus0, dtype=float))
    if out.code != K.FOUND:
        _miss(K.REASONS[out.code])
        return None
    return compiled_answer(qp, out, stage=stage)


def compiled_answer(qp: QPData, out, **fields) -> Solution:
    """A verified point from a compiled answering call (``out``, the :class:`._structs.Answer` of
    :func:`._fast.active_set_answer` or of :func:`._fast.ipm_answer` after its crossover) as a
    :class:`~.base.Solution`: the cones held with a positive multiplier and the bounds' guess become
    the next instant's :class:`ActiveSet`; the compiled uniqueness test's 1/0 ``unique=True`` / not
    proven (``None``, with ``unique_tested``: the least-norm stage need not test again);
    ``iterations`` the answer's; ``fields``: more of the solution's fields (``stage``)."""
    names = qp.cone_consts()[0]
    held, dirs = out.held, out.dirs
    nxt_cones = {}
    for k, h in enumerate(held.tolist()):  # (a plain loop over the few cones: no numpy index search per answer)
        if h:
            nxt_cones[names[k]] = (dirs[k], float(out.mus[k]))
    return Solution(out.x, OPTIMAL, float(out.objective), y=out.y, z=out.z, z_cone=out.z_cone,
                    active=ActiveSet(_EMPTY, _EMPTY, nxt_cones, out.next_state, (names, held, dirs),
                                     (out.x, out.mus)),
                    verified=True, unique=True if out.unique else None, unique_tested=True,
                    iterations=int(out.iterations), **fields)


def active_solution(qp, x, y, grad, state, cact, mus, dirs, nxt_state, **fields) -> Solution:
    """A verified active-set point as a :class:`~.base.Solution` (duals converted; ``fields``: more
    of its fields, e.g. ``stage``). The numpy reference of :func:`._fast.active_set_answer`'s
    answer."""
    z = np.where(state != 0, -grad, 0.0)
    held = np.flatnonzero(cact & (mus > 0))
    nxt_cones = {qp.cones[k].joint: (dirs[k], float(mus[k])) for k in held}
    return Solution(x, OPTIMAL, qp.objective(x), y=y, z=z,
                    z_cone=cone_duals(qp, np.where(cact, mus, 0.0), _force_directions(qp, x, dirs))
                    if qp.cones else np.zeros((0, 3)),
                    active=ActiveSet(_EMPTY, _EMPTY, nxt_cones, nxt_state), verified=True, **fields)


def _force_directions(qp, x, dirs) -> np.ndarray:
    """Each cone's force's unit direction across its axis at ``x``, ``dirs[k]`` where that part is
    at most 1e-12 of the force (:func:`._fast.held_direction` in numpy)."""
    G, g, ax = qp.cone_arrays()[:3]
    F = g + G @ x
    p = F - np.einsum("ka,ka->k", F, ax)[:, None] * ax
    perp = np.linalg.norm(p, axis=1)
    across = perp > 1e-12 * np.linalg.norm(F, axis=1)
    return np.where(across[:, None], p / np.where(across, perp, 1.0)[:, None], dirs)


_EMPTY = np.zeros(0, dtype=int)
_EMPTY_F = np.zeros(0)
_NO_MASK = np.zeros(0, dtype=np.bool_)
_NO_DIRS = np.zeros((0, 3))
MISSES: dict[str, int] = {}  # why guesses were rejected (counts, for profiling)


def _miss(reason: str) -> None:
    MISSES[reason] = MISSES.get(reason, 0) + 1


class WarmActiveSet(Stage):
    """Answering stage: the previous answer's active set (see the module docstring).

    Where that guess fails on a problem whose objective is diagonal and positive definite and which
    has no cones, a second guess comes from the problem's dual, climbed by Newton's method from the
    previous answer's multipliers (:mod:`._dual_guess`; ``settings.warm_dual_steps``): block
    principal pivoting from a guess several exchanges away can wander until its pivot limit. There
    the first guess gets ``settings.warm_dual_after`` pivots at most.

    Args:
        settings: the pivot limit per instant (``warm_max_pivots``, halved after each failure down to
            ``warm_min_pivots``, restored by a success or by an answer within ``warm_max_pivots``
            changes of the guess that failed), the dual guess's steps and the first guess's pivots
            before it, and the tolerances.
    """

    name = "warm_active_set"

    def __init__(self, settings: Settings = DEFAULT):
        self.settings = settings
        self.guess: ActiveSet | None = None
        self.y: np.ndarray | None = None  # the previous answer's equations' multipliers
        self.max_pivots = settings.warm_max_pivots  # this instant's limit
        self._failed: ActiveSet | None = None  # this instant's guess, where it failed

    def run(self, qp, sol, deadline):
        if self.guess is None or not jit.ready():
            return None
        s = self.settings
        dual = self._dual_applies(qp)
        # (where the second guess applies, the first gets fewer pivots: a guess that needs more than
        # a few is wandering, and the dual guess answers it for less)
        first = min(self.max_pivots, s.warm_dual_after) if dual else self.max_pivots
        out = try_active_set(qp, self.guess, first, stage=self.name, settings=s)
        if out is None and dual:
            out = self._dual_guess(qp)
        least = min(s.warm_min_pivots, s.warm_max_pivots)
        self.max_pivots = s.warm_max_pivots if out is not None else max(least, self.max_pivots // 2)
        self._failed = None if out is not None else self.guess  # (judged against the answer: learn)
        return out

    def _dual_applies(self, qp) -> bool:
        """Whether the second guess (class docstring) applies to ``qp``."""
        y = self.y
        return bool(self.settings.warm_dual_steps) and y is not None and not qp.cones and len(y) == len(qp.b) \
            and _separable(qp)

    def _dual_guess(self, qp) -> Solution | None:
        """The second guess (class docstring): :func:`dual_answer` from the last answer's
        multipliers."""
        s = self.settings
        return dual_answer(qp, self.y, s.warm_dual_steps, min(s.warm_min_pivots, s.warm_max_pivots), s, self.name)

    def learn(self, qp, sol):
        failed, self._failed = self._failed, None
        self.guess = sol.active if sol.active is not None else ActiveSet.from_duals(
            qp, sol, self.settings.active_set_from_solution)
        self.y = sol.y
        # a guess that failed with the answer within the pivot limit's reach of it (at most as many
        # bound and cone changes): the instants do not jump, and the next one, a like step from this
        # answer, gets the whole limit; halved there, each instant of a stretch of close ones would
        # get fewer pivots than it needs (docs/speed.md, "The pivot limit after a failure")
        if failed is not None and changes(qp, failed, self.guess) <= self.settings.warm_max_pivots:
            self.max_pivots = self.settings.warm_max_pivots

    def seed(self, hint):
        self.guess = hint.active
        self.y = hint.y

    def reset(self):
        self.guess = None
        self.y = None
        self.max_pivots = self.settings.warm_max_pivots
        self._failed = None


class DualActiveSet(Stage):
    """Answering stage for a cold instant (no previous answer: a first instant, or after ``reset``)
    of a problem whose objective is diagonal and positive definite (but on variables fixed by their
    bounds: :func:`_separable`) and which has no cones (case 1's ``f^T f``, the muscles'
    activations): the active set read off the dual's optimum, climbed by Newton's method from zero
    multipliers (:mod:`._dual_guess`, at most ``settings.cold_dual_steps`` steps), verified by the
    active-set solver within ``warm_max_pivots`` (:func:`dual_answer`; no pivot was spent on the
    instant before it, as the warm stage's second guess has spent some).
    Where it fails, the interior-point method answers. A warm instant's dual guess starts from the
    last answer's multipliers instead, in :class:`WarmActiveSet`; this stage then has nothing to say.

    On the shipped robots and the scaling study's chains it answers every cold instant of case 1
    with the optimum's exact KKT point, nearly always in one KKT solve, for a fraction of the
    interior-point method's time (docs/speed.md, "The cold instant's dual guess").
    """

    name = "dual_active_set"

    def __init__(self, settings: Settings = DEFAULT):
        self.settings = settings
        self.warm = False  # an answer (or a hint) to start from exists: the warm stage has the instant

    def run(self, qp, sol, deadline):
        s = self.settings
        if self.warm or not s.cold_dual_steps or qp.cones or not jit.ready() or not _separable(qp, fixed_ok=True):
            return None
        return dual_answer(qp, np.zeros(len(qp.b)), s.cold_dual_steps, s.warm_max_pivots, s, self.name)

    def learn(self, qp, sol):
        self.warm = True

    def seed(self, hint):
        self.warm = True

    def reset(self):
        self.warm = False


def dual_answer(qp: QPData, y0: np.ndarray, steps: int, pivots: int, settings: Settings,
                stage: str) -> Solution | None:
    """The optimum whose active set :func:`._dual_guess.dual_guess` reaches from the multipliers
    ``y0`` within ``steps`` Newton steps, verified by the active-set solver within ``pivots``;
    ``None`` where it fails. Its ``iterations`` count the Newton steps' linear systems with the KKT
    systems."""
    s = settings
    c, A, b, lb, ub = qp.kernel_arrays()[:5]
    d = np.ascontiguousarray(qp.P_diag, dtype=float)
    if not qp.strictly_convex():  # (zero only where a variable's bounds are one value: :func:`_separable`)
        d = np.where(d > 0.0, d, 1.0)
    state, made, _ = jit.kernels("solvers._dual_guess").dual_guess(
        d, c, A, b, lb, ub, np.ascontiguousarray(y0, dtype=float), steps, s.warm_dual_regularisation, s.warm_dual_tol)
    out = try_active_set(qp, ActiveSet(_EMPTY, _EMPTY, state=state), pivots, stage=stage, settings=s)
    return None if out is None else out.but(iterations=out.iterations + int(made))


def changes(qp: QPData, a: ActiveSet, b: ActiveSet) -> int:
    """How many of ``qp``'s variables have another bound (or none) in ``a`` than in ``b`` (each read
    as the warm start reads it: :meth:`ActiveSet.cable_state`), plus how many of its cones one holds
    and the other does not."""
    n = qp.n
    out = int(np.count_nonzero(a.cable_state(n) != b.cable_state(n)))
    if qp.cones:
        out += int(np.count_nonzero(a.cone_guess(qp)[0] != b.cone_guess(qp)[0]))
    return out


def _separable(qp: QPData, fixed_ok: bool = False) -> bool:
    """Whether ``qp``'s objective is ``diag(P_diag)`` (no factor rows) with every entry positive, or
    (``fixed_ok``) zero only on variables whose two bounds are one value: a muscle whose force range
    is a single value at this state has no activation to weigh. Such a variable is at its bound
    whatever the multipliers, so the dual guess takes it with any positive curvature
    (:func:`dual_answer`). The cold stage asks with ``fixed_ok``; the warm stage, which asks at every
    instant, does not: that test costs numpy calls where the first costs none (docs/speed.md, "The
    cold instant's dual guess")."""
    if qp.P_factor is None or qp.P_factor.shape[0] != 0:
        return False
    if qp.strictly_convex():
        return True
    d = qp.P_diag
    if not fixed_ok or d is None or d.size == 0:
        return False
    off = ~(d > 0.0)
    return bool(np.all(d[off] == 0.0) and np.all(qp.lb[off] == qp.ub[off]) and np.all(np.isfinite(qp.lb[off])))


class Polish(Stage):
    """Refining stage: the exact KKT point of the active set of another stage's answer (bounds and
    the equation of motion then hold to rounding instead of to that stage's tolerance), if it
    verifies; the answer unchanged otherwise (pivot limit ``settings.polish_max_pivots``)."""

    name = "polish"
    refines = True

    def __init__(self, settings: Settings = DEFAULT):
        self.settings = settings

    def run(self, qp, sol, deadline):
        if sol.active is not None:  # an active-set stage's answer is exact already
            return sol
        if sol.unique is False:  # the least-norm optimum (a constant objective's): another point would not be
            return sol
        if not jit.ready():  # kernels switched off (a test's numpy reference): bounds-only polish in numpy
            hit = numpy_polish(qp, sol, self.settings)
            return sol if hit is None else hit.but(stage=f"{sol.stage}>{self.name}", iterations=sol.iterations,
                                                    rounds=sol.rounds, message=sol.message)
        s = self.settings
        hit = try_active_set(qp, ActiveSet.from_duals(qp, sol, s.active_set_from_solution), s.polish_max_pivots,
                             settings=s)
        if hit is None:
            return sol
        return hit.but(stage=f"{sol.stage}>{self.name}", iterations=sol.iterations, rounds=sol.rounds,
                       message=sol.message)


def numpy_polish(qp: QPData, sol: Solution, settings: Settings = DEFAULT) -> Solution | None:
    """The polish without the compiled kernels, where no cone binds: the exact KKT point of the
    bounds that ``sol``'s multipliers hold (a least-squares solve of the KKT system, so a dependent
    equation does no harm), kept if the freed variables stay within their bounds and the held ones'
    multipliers keep their sign; ``None`` otherwise (the answer stays as it is). An interior point
    leaves the held variables ~1e-10 off their bounds, which at forces of 1 mN fails the KKT check's
    complementarity (the 2-link arm at rest, case 1, on the uncompiled path)."""
    if sol.z is None or not np.all(np.isfinite(sol.x)):
        return None
    grad = qp.gradient(sol.x)
    thr = 1e-9 * max(np.abs(grad).max(initial=0.0), np.abs(qp.c).max(initial=0.0), 1e-300)
    if qp.cones and (sol.z_cone is None or np.abs(sol.z_cone).max(initial=0.0) > thr):
        return None  # a binding cone: nonlinear, the compiled active set's job
    up, lo = sol.z > thr, sol.z < -thr
    held = up | lo
    x = sol.x.copy()
    x[up], x[lo] = qp.ub[up], qp.lb[lo]
    F = np.flatnonzero(~held)
    n_eq = len(qp.b)
    P = qp.P
    K = np.zeros((len(F) + n_eq, len(F) + n_eq))
    K[:len(F), :len(F)] = P[np.ix_(F, F)]
    K[:len(F), len(F):] = qp.A[:, F].T
    K[len(F):, :len(F)] = qp.A[:, F]
    rhs = np.concatenate([-(qp.c[F] + P[np.ix_(F, np.flatnonzero(held))] @ x[held]),
                          qp.b - qp.A[:, held] @ x[held]])
    sol_k = np.linalg.lstsq(K, rhs, rcond=None)[0]
    x[F] = sol_k[:len(F)]
    y = sol_k[len(F):]
    if len(qp.b) and not _eom_met(qp, x, settings.eom_rel):  # the held bounds leave the equations unmet (rounding-size
        return None                        # multipliers of a constant objective read as binding)
    slack = 1e-12 * (1.0 + np.maximum(np.abs(qp.lb), np.abs(qp.ub)))
    if np.any(x[F] < qp.lb[F] - slack[F]) or np.any(x[F] > qp.ub[F] + slack[F]):
        return None
    z = np.zeros(qp.n)
    z[held] = -(qp.gradient(x) + qp.A.T @ y)[held]
    if np.any(z[up] < 0) or np.any(z[lo] > 0):
        return None
    x = np.clip(x, qp.lb, qp.ub)
    zc = None if not qp.cones else np.zeros((len(qp.cones), 3))
    return Solution(x, OPTIMAL, qp.objective(x), y=y, z=z, z_cone=zc, verified=False)


def _eom_met(qp: QPData, x, eom_rel: float) -> bool:
    """``A x = b`` to the answer check's tolerance (``eom_rel``: :attr:`~mcdm_pin.settings.Settings.eom_rel`)."""
    scale = max(np.abs(qp.b).max(initial=0.0), (np.abs(qp.A) @ np.abs(x)).max(initial=0.0), 1e-300)
    return bool(np.abs(qp.A @ x - qp.b).max(initial=0.0) <= eom_rel * scale)


def warm_calls():
    """The warm path's compiled entry points (:mod:`._fast`: the active-set answer and the answer's
    checks; :mod:`._dual_guess`), with example arguments of the types the library passes."""
    z, n = np.zeros, 2
    return _fast.warm_calls() + [(_dual_guess.dual_guess, (np.ones(n), z(n), z((1, n)), z(1), z(n), z(n), z(1), 2,
                                                           1e-6, 1e-9))]


def _register() -> None:
    # loaded and compiled with the solvers' kernels (this module is imported by
    # mcdm_pin.solvers.ipm, one of jit.MODULES)
    jit.register("mcdm_pin.solvers.active_set", warm_calls)


_register()
