r"""Active-set warm start: try the previous instant's active set first, accept only a verified KKT point.

Along a trajectory the set of cables at a bound and of cones that bind changes rarely. Given such a
guess — cables fixed at ``f_min`` (``lower``) or ``f_max`` (``upper``), cones held on their surface —
the optimum for that active set solves an equality-constrained problem: one linear KKT system for the
bounds, a few Newton (SQP) steps for the cones (each cone's surface
:math:`c_k(f) = \|F_\perp\| - \tan\rho^*_k\, a^T F = 0` linearised, its curvature weighted by its
multiplier). The point is returned only if it satisfies *all* the KKT conditions of the full convex
problem to tight tolerances:

- primal: equation of motion, every bound, every inactive cone (within its angle), active cones on
  the right nappe (``a . F > 0``);
- dual: multipliers of the fixed bounds and active cones have the right sign;
- stationarity on the free cables (by construction, checked).

For a convex problem these conditions are sufficient: a verified point is a global optimum. When any
check fails (the active set changed, a singular system, ...) the caller falls back to the full
solver, whose answer gives the next guess.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..problem import QPData
from . import _kkt as K

# tolerances of the verification, relative to the problem's scale
_PRIMAL_TOL = 1e-12  # bounds: |violation| <= tol * (1 + |bound|)
_DUAL_TOL = 1e-9  # multipliers: >= -tol * gradient scale
_EOM_TOL = 1e-11  # equation of motion, relative
_REG = 1e-12  # Tikhonov term on the free cables, relative to the objective's scale (see _kkt.eq_solve)
_STEP_TOL = 1e-10  # Newton step for cones, relative (the KKT solve's rounding floor is ~1e-11)


@dataclass
class ActiveSet:
    """A guess: index arrays of cables at their lower/upper bound, and per cone joint its surface
    direction (unit vector of F_perp) and multiplier when it binds. ``state``, when given (the
    compiled solver's own output), takes the place of ``lower`` and ``upper``."""

    lower: np.ndarray
    upper: np.ndarray
    cones: dict = field(default_factory=dict)  # joint -> (direction (3,), multiplier)
    state: np.ndarray | None = None  # the same as int8 codes per cable (0 free, 1 lower, 2 upper)

    def cable_state(self, n: int) -> np.ndarray:
        if self.state is not None and self.state.shape == (n,):
            return self.state
        state = np.zeros(n, dtype=np.int8)
        state[self.lower] = 1
        state[self.upper] = 2
        return state

    @classmethod
    def from_solution(cls, qp: QPData, f: np.ndarray, cone_mult: dict, bound_mult=None,
                      tol: float = 1e-8):
        """The active set of a solution: cables within ``tol`` (relative) of a bound whose
        multiplier pushes them onto it (``bound_mult``: > 0 at a lower bound, < 0 at an upper bound;
        None: position only), and cones with a positive multiplier."""
        near_l = f - qp.lb <= tol * (1.0 + np.abs(qp.lb))
        near_u = qp.ub - f <= tol * (1.0 + np.abs(qp.ub))
        if bound_mult is not None:
            thr = 1e-12 * max(np.abs(bound_mult).max(initial=0.0), 1e-300)
            near_l &= bound_mult > thr
            near_u &= bound_mult < -thr
        cones = {}
        if qp.cones:
            G, gc, ax, _, _ = qp.cone_arrays()
            F = gc + G @ f
            perp = F - np.einsum("ka,ka->k", ax, F)[:, None] * ax
            norm = np.sqrt(np.einsum("ka,ka->k", perp, perp))
            along = np.einsum("ka,ka->k", ax, F)
            tan = qp.cone_arrays()[3]
            for k, cone in enumerate(qp.cones):
                mult = cone_mult.get(cone.joint, 0.0)
                # binding: a positive multiplier and the force on the cone's surface (a cutting-plane
                # solver reports tiny positive multipliers on cuts of cones that do not bind)
                if mult > 0 and norm[k] > 0 and norm[k] >= tan[k] * along[k] * (1.0 - tol):
                    cones[cone.joint] = (perp[k] / norm[k], mult)
        return cls(np.flatnonzero(near_l), np.flatnonzero(near_u), cones)


def try_active_set(qp: QPData, guess: ActiveSet, max_pivots: int = 30, max_newton: int = 10):
    """The verified optimum, as ``(f, cone_multipliers, bound_multipliers, next_guess)``, or
    ``None``; ``next_guess`` is the optimum's active set (for the next instant).

    Starting from ``guess``, the active set is corrected by block principal pivoting (free cables
    that leave their bounds are fixed there, fixed cables whose multiplier has the wrong sign are
    freed, broken cones join, cones with a negative multiplier leave) for at most ``max_pivots``
    equality-constrained solves; a repeated active set stops it. The loop runs compiled
    (:func:`._kkt.active_set_solve`).
    """
    G, gc, ax, tn, basis0 = qp.cone_arrays()
    state = guess.cable_state(qp.n)
    if qp.cones:
        names = [c.joint for c in qp.cones]
        cact = np.array([nm in guess.cones for nm in names], dtype=np.bool_)
        cdir = np.array([guess.cones[nm][0] if nm in guess.cones else (0.0, 0.0, 0.0) for nm in names],
                        dtype=float)
    else:
        names, cact, cdir = [], _NO_CONES, _NO_DIRS
    # C-ordered float arrays and Python scalars: one compiled specialisation serves every call
    # (each array layout would cost numba another ~20 s of compilation)
    c_ = np.ascontiguousarray
    code, f, mus, grad, state, cact, dirs, nxt_state = K.active_set_solve(
        c_(qp.H, dtype=float), c_(qp.c, dtype=float), c_(qp.A, dtype=float), c_(qp.b, dtype=float),
        c_(qp.lb, dtype=float), c_(qp.ub, dtype=float), state, c_(G, dtype=float), c_(gc, dtype=float),
        c_(ax, dtype=float), c_(tn, dtype=float), c_(basis0, dtype=float), cact, c_(cdir, dtype=float),
        int(max_pivots), int(max_newton), _STEP_TOL, _PRIMAL_TOL, _DUAL_TOL, _EOM_TOL, _REG)
    if code != K.FOUND:
        return _miss(K.REASONS[code])
    if names:
        active = np.flatnonzero(cact)
        mult = {names[k]: float(mus[k]) for k in active}
        nxt_cones = {names[k]: (dirs[k], float(mus[k])) for k in active if mus[k] > 0}
    else:
        mult, nxt_cones = {}, {}
    # the next instant's guess (as ActiveSet.from_solution would find it: bounds whose multiplier is
    # not negligible, cones with a positive multiplier)
    nxt = ActiveSet(_EMPTY, _EMPTY, nxt_cones, nxt_state)
    return f, mult, grad, nxt


_NO_CONES = np.zeros(0, dtype=np.bool_)
_NO_DIRS = np.zeros((0, 3))
_EMPTY = np.zeros(0, dtype=int)
MISSES: dict[str, int] = {}  # why guesses were rejected (counts, for profiling)


def _miss(reason: str):
    MISSES[reason] = MISSES.get(reason, 0) + 1
    return None
