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
_STEP_TOL = 1e-10  # Newton step for cones, relative (the KKT solve's rounding floor is ~1e-11)


@dataclass
class ActiveSet:
    """A guess: index arrays of cables at their lower/upper bound, and per cone joint its surface
    direction (unit vector of F_perp) and multiplier when it binds."""

    lower: np.ndarray
    upper: np.ndarray
    cones: dict = field(default_factory=dict)  # joint -> (direction (3,), multiplier)

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
            for k, cone in enumerate(qp.cones):
                mult = cone_mult.get(cone.joint, 0.0)
                if mult > 0 and norm[k] > 0:
                    cones[cone.joint] = (perp[k] / norm[k], mult)
        return cls(np.flatnonzero(near_l), np.flatnonzero(near_u), cones)


def try_active_set(qp: QPData, guess: ActiveSet, max_pivots: int = 12, max_newton: int = 10):
    """The verified optimum, as ``(f, cone_multipliers, bound_multipliers, next_guess)``, or
    ``None``; ``next_guess`` is the optimum's active set (for the next instant).

    Starting from ``guess``, the active set is corrected by block principal pivoting (free cables
    that leave their bounds are fixed there, fixed cables whose multiplier has the wrong sign are
    freed, broken cones join, cones with a negative multiplier leave) for at most ``max_pivots``
    equality-constrained solves; a repeated active set stops it. The solves and checks are the
    compiled kernels of :mod:`._kkt`; a non-square or singular system falls back to the numpy
    formulation (:func:`_solve_equality`, least squares).
    """
    n, neq = qp.n, len(qp.b)
    H, g = qp.H, qp.c
    G, gc, ax, tn, basis0 = qp.cone_arrays()
    names = [c.joint for c in qp.cones]
    state = np.zeros(n, dtype=np.int8)
    state[guess.lower] = 1
    state[guess.upper] = 2
    cact = np.zeros(len(names), dtype=np.bool_)
    cdir = np.zeros((len(names), 3))
    for k, name in enumerate(names):
        if name in guess.cones:
            cact[k] = True
            cdir[k] = guess.cones[name][0]
    seen = set()
    for _ in range(max_pivots):
        key = state.tobytes() + cact.tobytes()
        if key in seen:
            return _miss("the active set cycles")
        seen.add(key)
        code, f, y, mus, dirs = K.eq_solve(H, g, qp.A, qp.b, qp.lb, qp.ub, state, G, gc, ax, tn, cact,
                                           cdir, max_newton, _STEP_TOL)
        if code in (K.SINGULAR, K.NOT_SQUARE):
            out = _solve_equality(qp, np.flatnonzero(state == 1), np.flatnonzero(state == 2),
                                  {names[k]: (cdir[k], 0.0) for k in np.flatnonzero(cact)}, max_newton)
            if isinstance(out, str):
                return _miss(out)
            if isinstance(out[0], str):  # ("drop", joints)
                cact &= ~np.isin(names, list(out[1]))
                continue
            f, y, active, mu_list = out
            mus = np.zeros(len(names))
            dirs = cdir.copy()
            for (cone, d), mu in zip(active, mu_list):
                mus[names.index(cone.joint)] = mu
                dirs[names.index(cone.joint)] = d
        elif code == K.VANISHED:
            return _miss("a cone's force vanished")
        elif code == K.NO_CONVERGENCE:
            return _miss("Newton steps on the cone surfaces did not converge")
        elif code == K.DROP:  # a cone pulls the force inwards: it is not active
            cact &= ~(mus < 0)
            continue
        (vcode, to_lower, to_upper, release, cone_in, cone_dir, cone_out, grad, worst_kind,
         worst_idx) = K.verify(H, g, qp.A, qp.b, qp.lb, qp.ub, state, f, y, G, gc, ax, tn, basis0,
                               cact, mus, _PRIMAL_TOL, _DUAL_TOL, _EOM_TOL)
        if vcode != K.KKT_PIVOT:
            if vcode == K.KKT_OPTIMAL:
                mult = {names[k]: float(mus[k]) for k in np.flatnonzero(cact)}
                # the next instant's guess (as ActiveSet.from_solution would find it: bounds whose
                # multiplier is not negligible, cones with a positive multiplier)
                thr = 1e-12 * max(float(np.abs(grad).max(initial=0.0)), 1e-300)
                nxt = ActiveSet(np.flatnonzero((state == 1) & (grad > thr)),
                                np.flatnonzero((state == 2) & (grad < -thr)),
                                {names[k]: (dirs[k], float(mus[k])) for k in np.flatnonzero(cact)
                                 if mus[k] > 0})
                return f, mult, grad, nxt
            return _miss(_VERIFY_REASONS[vcode])
        new_state = state.copy()
        new_state[release] = 0
        new_state[to_lower] = 1
        new_state[to_upper] = 2
        need = neq + int(cact.sum()) - int(cone_out.sum()) + int(cone_in.sum())
        if n - int(np.count_nonzero(new_state)) < need:
            # the block pivot would fix too many cables: change only the worst violation and, if
            # still too few cables are free, free the least binding fixed ones (a simplex-like swap)
            new_state = state.copy()
            if worst_kind in (1, 2):
                new_state[worst_idx] = worst_kind
                cone_in[:] = False
                cone_out[:] = False
            elif worst_kind == 0:
                new_state[worst_idx] = 0
            need = neq + int(cact.sum()) - int(cone_out.sum()) + int(cone_in.sum())
            fixed = np.flatnonzero(new_state != 0)
            fixed = fixed[fixed != worst_idx]
            lam = np.where(new_state[fixed] == 1, grad[fixed], -grad[fixed])
            for i in fixed[np.argsort(lam, kind="stable")]:
                if n - int(np.count_nonzero(new_state)) >= need:
                    break
                new_state[i] = 0
        state = new_state
        cact &= ~cone_out
        cact |= cone_in
        cdir = np.where(cone_in[:, None], cone_dir, dirs)
    return _miss("no verified point within the pivot limit")


_VERIFY_REASONS = {K.KKT_EOM: "equation of motion not met", K.KKT_NAPPE: "a cone's force on the wrong nappe",
                   K.KKT_STATIONARY: "not stationary"}


def _curvature_of(cone, f):
    F = cone.force(f)
    perp = F - float(cone.axis @ F) * cone.axis
    norm = float(np.linalg.norm(perp))
    if norm <= 1e-300:
        return None, None
    nhat = perp / norm
    Pp = np.eye(3) - np.outer(cone.axis, cone.axis) - np.outer(nhat, nhat)
    return nhat, cone.G.T @ Pp @ cone.G / norm


def _solve_equality(qp: QPData, lower, upper, guess_cones: dict, max_newton: int):
    """Minimise with the given bounds fixed and cones on their surface: one KKT solve without
    cones, Newton steps with. Returns (f, y, [(cone, dir)], multipliers) or a reason string."""
    n = qp.n
    H, g = 2.0 * qp.P, qp.c
    if len(np.intersect1d(lower, upper)):
        return "a cable at both bounds"
    fixed = np.zeros(n, dtype=bool)
    fixed[lower] = True
    fixed[upper] = True
    free = ~fixed
    f = np.empty(n)
    f[lower] = qp.lb[lower]
    f[upper] = qp.ub[upper]
    by_name = {c.joint: c for c in qp.cones}
    active = [(by_name[j], d) for j, (d, _) in guess_cones.items() if j in by_name]
    nf, neq, nc = int(free.sum()), len(qp.b), len(active)
    # fewer free cables than equations is fine when the equations are dependent (e.g. the 2-link
    # arm at q = 0): the KKT system is then solved in the least-squares sense and verified
    square = nf >= neq + nc
    A_F = qp.A[:, free]
    rhs_eq = qp.b - qp.A[:, fixed] @ f[fixed]
    H_FF, H_FB = H[np.ix_(free, free)], H[np.ix_(free, fixed)]
    mus = np.zeros(nc)
    f_cur, x_prev = None, None
    for _ in range(max_newton if nc else 1):
        K = np.zeros((nf + neq + nc, nf + neq + nc))
        K[:nf, :nf] = H_FF
        K[:nf, nf:nf + neq] = A_F.T
        K[nf:nf + neq, :nf] = A_F
        rhs = np.empty(nf + neq + nc)
        gk = g
        if nc:
            gk = g.copy()
            rows, rrhs = [], []
            for k, (cone, d) in enumerate(active):
                if f_cur is not None:
                    d2, D = _curvature_of(cone, f_cur)
                    if d2 is None:
                        return "a cone's force vanished"
                    active[k] = (cone, d2)
                    d = d2
                    # curvature centred at the current point: + 1/2 (f - f_cur)^T D (f - f_cur)
                    D = max(mus[k], 0.0) * D
                    K[:nf, :nf] += D[np.ix_(free, free)]
                    gk = gk - D @ f_cur
                    gk[free] += D[np.ix_(free, fixed)] @ f[fixed]
                w = d - cone.tan * cone.axis
                rows.append(w @ cone.G)
                rrhs.append(-(w @ cone.g))
            Cc = np.array(rows)
            K[:nf, nf + neq:] = Cc[:, free].T
            K[nf + neq:, :nf] = Cc[:, free]
            rhs[nf + neq:] = np.array(rrhs) - Cc[:, fixed] @ f[fixed]
        rhs[:nf] = -(gk[free] + H_FB @ f[fixed])
        rhs[nf:nf + neq] = rhs_eq
        try:
            if not square:
                raise np.linalg.LinAlgError
            sol = np.linalg.solve(K, rhs)
        except np.linalg.LinAlgError:
            sol = np.linalg.lstsq(K, rhs, rcond=None)[0]
            if np.abs(K @ sol - rhs).max(initial=0.0) > 1e-10 * max(np.abs(rhs).max(initial=0.0), 1.0):
                return "singular KKT system"
        if not np.all(np.isfinite(sol)):
            return "singular KKT system"
        x = sol[:nf]
        y = sol[nf:nf + neq]
        mus = sol[nf + neq:]
        f[free] = x
        if not nc:
            break
        if f_cur is not None and np.any(mus < 0):
            # a cone pulls the force inwards: it is not active, drop it and re-solve
            return ("drop", {cone.joint for (cone, _), mu in zip(active, mus) if mu < 0})
        if x_prev is not None and np.linalg.norm(x - x_prev) <= _STEP_TOL * (1.0 + np.linalg.norm(x)):
            break
        x_prev = x.copy()
        f_cur = f.copy()
    else:
        return "Newton steps on the cone surfaces did not converge"
    return f, y, active, mus


MISSES: dict[str, int] = {}  # why guesses were rejected (counts, for profiling)


def _miss(reason: str):
    MISSES[reason] = MISSES.get(reason, 0) + 1
    return None
