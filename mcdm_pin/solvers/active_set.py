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
        for cone in qp.cones:
            mult = cone_mult.get(cone.joint, 0.0)
            F = cone.force(f)
            perp = F - float(cone.axis @ F) * cone.axis
            norm = float(np.linalg.norm(perp))
            if mult > 0 and norm > 0:
                cones[cone.joint] = (perp / norm, mult)
        return cls(np.flatnonzero(near_l), np.flatnonzero(near_u), cones)


def try_active_set(qp: QPData, guess: ActiveSet, max_pivots: int = 12, max_newton: int = 10):
    """The verified optimum, as ``(f, cone_multipliers, bound_multipliers)``, or ``None``.

    Starting from ``guess``, the active set is corrected by block principal pivoting (free cables
    that leave their bounds are fixed there, fixed cables whose multiplier has the wrong sign are
    freed, broken cones join, cones with a negative multiplier leave) for at most ``max_pivots``
    equality-constrained solves; a repeated active set stops it.
    """
    lower, upper = set(guess.lower.tolist()), set(guess.upper.tolist())
    cones = dict(guess.cones)
    seen = set()
    for _ in range(max_pivots):
        key = (frozenset(lower), frozenset(upper), frozenset(cones))
        if key in seen:
            return _miss("the active set cycles")
        seen.add(key)
        out = _solve_equality(qp, np.array(sorted(lower), dtype=int), np.array(sorted(upper), dtype=int),
                              cones, max_newton)
        if isinstance(out, str):
            return _miss(out)
        if isinstance(out[0], str):  # ("drop", joints)
            for j in out[1]:
                cones.pop(j, None)
            continue
        f, y, active, mus = out
        verdict = _verify(qp, f, y, active, mus, lower, upper)
        if isinstance(verdict, str):
            return _miss(verdict)
        if isinstance(verdict, tuple) and verdict[0] is True:
            return f, {cone.joint: float(mu) for (cone, _), mu in zip(active, mus)}, verdict[1]
        to_lower, to_upper, release, cone_in, cone_out, worst, grad = verdict
        new_lower = (lower - release) | to_lower
        new_upper = (upper - release) | to_upper
        n_cones = len(cones) - len(cone_out) + len(cone_in)
        need = len(qp.b) + n_cones  # equations on the free cables
        if qp.n - len(new_lower) - len(new_upper) < need:
            # the block pivot would fix too many cables: change only the worst violation and, if
            # still too few cables are free, free the least binding fixed ones (a simplex-like swap)
            kind, idx = worst
            if kind == "lower":
                new_lower, new_upper = lower | {idx}, set(upper)
            elif kind == "upper":
                new_lower, new_upper = set(lower), upper | {idx}
            else:
                new_lower, new_upper = lower - {idx}, upper - {idx}
            if kind in ("lower", "upper"):
                cone_in, cone_out = {}, set()
            need = len(qp.b) + len(cones) - len(cone_out) + len(cone_in)
            lam = {i: grad[i] for i in new_lower if i != idx}
            lam.update({i: -grad[i] for i in new_upper if i != idx})
            for i in sorted(lam, key=lam.get):
                if qp.n - len(new_lower) - len(new_upper) >= need:
                    break
                new_lower.discard(i)
                new_upper.discard(i)
        lower, upper = new_lower, new_upper
        for j in cone_out:
            cones.pop(j, None)
        for j, d in cone_in.items():
            cones[j] = (d, 0.0)
    return _miss("no verified point within the pivot limit")


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


def _verify(qp, f, y, active, mus, lower: set, upper: set):
    """KKT conditions of the full problem at ``f``.

    Returns (True, bound multipliers) at a global optimum, a reason string (give up), or the
    pivots that would repair
    the active set: (to_lower, to_upper, release, cones_in {joint: dir}, cones_out)."""
    tol_l = _PRIMAL_TOL * (1.0 + np.abs(qp.lb))
    tol_u = _PRIMAL_TOL * (1.0 + np.abs(qp.ub))
    to_lower = set(np.flatnonzero(f < qp.lb - tol_l).tolist()) - lower
    to_upper = set(np.flatnonzero(f > qp.ub + tol_u).tolist()) - upper
    res = qp.A @ f - qp.b
    scale = max(np.abs(qp.b).max(initial=0.0), (np.abs(qp.A) @ np.abs(f)).max(initial=0.0), 1e-300)
    if np.abs(res).max(initial=0.0) > _EOM_TOL * scale:
        return "equation of motion not met"
    active_names = {cone.joint for cone, _ in active}
    cones_in, cones_out = {}, set()
    for cone in qp.cones:
        F = cone.force(f)
        along = float(cone.axis @ F)
        perp_vec = F - along * cone.axis
        perp = float(np.linalg.norm(perp_vec))
        if cone.joint in active_names:
            if along <= 0:
                return "a cone's force on the wrong nappe"
        elif perp > cone.tan * along * (1 + 1e-12) or along < 0:
            cones_in[cone.joint] = perp_vec / perp if perp > 0 else cone.basis[0]
    for (cone, _), mu in zip(active, mus):
        if mu < 0:
            cones_out.add(cone.joint)
    obj_grad = 2.0 * (qp.P @ f) + qp.c
    Aty = qp.A.T @ y
    grad = obj_grad + Aty
    for (cone, _), mu in zip(active, mus):
        F = cone.force(f)
        perp = F - float(cone.axis @ F) * cone.axis
        nhat = perp / np.linalg.norm(perp)
        grad = grad + mu * ((nhat - cone.tan * cone.axis) @ cone.G)
    gscale = max(np.abs(obj_grad).max(initial=0.0), np.abs(Aty).max(initial=0.0), 1e-300)
    fixed = np.zeros(qp.n, dtype=bool)
    fixed[list(lower | upper)] = True
    if np.abs(grad[~fixed]).max(initial=0.0) > 1e-8 * gscale:
        return "not stationary"
    lo = np.array(sorted(lower), dtype=int)
    up = np.array(sorted(upper), dtype=int)
    release = set(lo[grad[lo] < -_DUAL_TOL * gscale].tolist()) | \
        set(up[grad[up] > _DUAL_TOL * gscale].tolist())
    if not (to_lower or to_upper or release or cones_in or cones_out):
        return True, grad
    # the single worst violation, relative: primal in force, dual in gradient units
    cands = [(float((qp.lb[i] - f[i]) / (1.0 + abs(qp.lb[i]))), ("lower", i)) for i in to_lower]
    cands += [(float((f[i] - qp.ub[i]) / (1.0 + abs(qp.ub[i]))), ("upper", i)) for i in to_upper]
    cands += [(float(abs(grad[i]) / gscale), ("release", i)) for i in release]
    worst = max(cands)[1] if cands else ("none", -1)
    return to_lower, to_upper, release, cones_in, cones_out, worst, grad
