r"""The answer check every back-end's answer passes before it is called optimal, and the projection
onto the bounds.

:func:`kkt_residuals` measures, at a :class:`~.base.Solution`, the Karush-Kuhn-Tucker conditions of the
convex problem (:class:`~mcdm_pin.qp.QPData`; duals as in :mod:`.base`):

- primal: equation of motion (relative), bounds (absolute), cones (degrees);
- stationarity: ``|P x + c + A^T y + z - sum_k T_k^T z_k|_inf`` relative to the largest of its terms,
  and of ``max_i sum_j |P_ij| |x_j|`` (the size of ``P x`` before cancellation: an objective constant
  on the feasible set, e.g. a planar robot's interactions, has a gradient of rounding size there);
  for a constant objective (``P = 0``, ``c = 0``: every weight zero) at least the absolute
  ``KKT_GRAD_FLOOR``, since its multipliers are of rounding size, ~1e-22, noise relative to themselves;
- dual feasibility and complementarity: ``sum_i z_i^+ (u_i - x_i) + z_i^- (x_i - l_i) + sum_k
  z_k . s_k`` (the duality gap of the Lagrangian), relative to the multipliers' size times the
  variables' size, and every cone dual in the second-order cone.

For a convex problem these conditions are sufficient: an answer that meets them is optimal to the
stated tolerances (the acceptance fields of :class:`mcdm_pin.settings.Settings`), whatever produced
it. An answer without duals is checked for feasibility only.
"""

from __future__ import annotations

import numpy as np

from .. import jit
from ..settings import DEFAULT, Settings
from ._structs import Cones
from .base import INACCURATE, OPTIMAL, Solution, Stage, cone_violation_deg


def eom_residual(qp, x) -> float:
    """``|A x - b|_inf / max(|b|_inf, max_i sum_j |A_ij x_j|)``."""
    if not len(qp.b):
        return 0.0
    r = qp.A @ x - qp.b
    scale = max(np.abs(qp.b).max(initial=0.0), (np.abs(qp.A) @ np.abs(x)).max(initial=0.0), 1e-300)
    return float(np.abs(r).max(initial=0.0) / scale)


def kkt_residuals(qp, sol: Solution, settings: Settings = DEFAULT) -> dict:
    """The residuals described in the module docstring (``stationarity`` and ``complementarity`` are
    NaN when the solution has no duals; ``settings``: the gradient floor ``kkt_grad_floor``). One
    compiled pass (:func:`._fast.kkt_measures`); :func:`numpy_kkt_residuals` is its reference."""
    if not jit.ready():
        return numpy_kkt_residuals(qp, sol, settings)
    c_ = np.ascontiguousarray
    c, A, b, lb, ub, G, g, ax, tn, basis0 = qp.kernel_arrays()
    n, K = qp.n, len(qp.cones)
    duals = not (sol.y is None or sol.z is None or (qp.cones and sol.z_cone is None))
    if qp.structured:
        H, d0, F = _NO_H, c_(qp.P_diag, dtype=float), c_(qp.P_factor, dtype=float).reshape(-1, n)
    else:
        H, d0, F = c_(qp.P, dtype=float), _NO_D, _NO_H
    _, angles, cosr, basis = qp.cone_consts()
    cones = Cones(G, g, ax, tn, basis0, cosr, basis)  # (the kernel makes the cones' rows from them)
    floor = settings.kkt_grad_floor if duals and qp.constant_objective() else 1e-300
    m = jit.kernels("solvers._fast").kkt_measures(  # (plain tuples at the boundary: ._structs; a QP's fields)
        (H, d0, F, c, float(qp.r), A, b, lb, ub, False), tuple(cones), c_(angles, dtype=float), c_(sol.x, dtype=float),
        c_(sol.y, dtype=float) if duals else _NO_D, c_(sol.z, dtype=float) if duals else _NO_D,
        c_(sol.z_cone, dtype=float).reshape(K, 3) if duals and K else np.zeros((K, 3)), duals, floor)
    return m._asdict()


_NO_D = np.zeros(0)
_NO_H = np.zeros((0, 0))


def numpy_kkt_residuals(qp, sol: Solution, settings: Settings = DEFAULT) -> dict:
    """:func:`kkt_residuals` in numpy (the compiled pass's reference)."""
    x = sol.x
    out = dict(eom=eom_residual(qp, x),
               bound=float(max((qp.lb - x).max(initial=0.0), (x - qp.ub).max(initial=0.0))),
               cone_deg=float(cone_violation_deg(qp, x).max(initial=0.0)),
               stationarity=float("nan"), complementarity=float("nan"))
    if sol.y is None or sol.z is None or (qp.cones and sol.z_cone is None):
        return out
    grad = qp.gradient(x)
    Aty = qp.A.T @ sol.y if len(qp.b) else np.zeros(qp.n)
    terms = [np.abs(grad - qp.c).max(initial=0.0), np.abs(qp.c).max(initial=0.0),
             np.abs(Aty).max(initial=0.0), np.abs(sol.z).max(initial=0.0),
             _hessian_size(qp, x), settings.kkt_grad_floor if qp.constant_objective() else 1e-300]
    g = grad + Aty + sol.z
    comp = 0.0
    if qp.cones:
        T, t = qp.cone_rows()
        lam = sol.z_cone
        Tl = np.einsum("kan,ka->n", T, lam)
        terms.append(np.abs(Tl).max(initial=0.0))
        g = g - Tl
        s = np.einsum("kan,n->ka", T, x) + t
        comp += float(np.abs(np.einsum("ka,ka->k", lam, s)).sum())
        # every dual in the cone (to rounding)
        lam_out = np.maximum(np.linalg.norm(lam[:, 1:], axis=1) - lam[:, 0], 0.0)
        comp += float(lam_out.sum() * (1.0 + np.abs(s).max(initial=0.0)))
    gscale = max(terms)
    out["stationarity"] = float(np.abs(g).max(initial=0.0) / gscale)
    z = sol.z
    up, lo = np.maximum(z, 0.0), np.maximum(-z, 0.0)
    with np.errstate(invalid="ignore"):
        comp += float(np.where(up > 0, up * (qp.ub - x), 0.0).sum())
        comp += float(np.where(lo > 0, lo * (x - qp.lb), 0.0).sum())
    # the variables' size (not the bounds': at forces of 0.02 N under limits of 2000 N a gap relative
    # to the limits let a point 2e-5 N off its bounds pass)
    bounds = np.concatenate([np.abs(qp.lb[np.isfinite(qp.lb)]), np.abs(qp.ub[np.isfinite(qp.ub)])])
    xscale = max(np.abs(x).max(initial=0.0), 1e-12 * bounds.max(initial=0.0), 1e-300)
    den = gscale * xscale  # (0 where every term and variable is 0: then a gap is all there is)
    if not np.isfinite(comp):
        out["complementarity"] = float("inf")
    else:
        out["complementarity"] = float(abs(comp) / den) if den > 0.0 else (0.0 if comp == 0.0 else float("inf"))
    return out


def _hessian_size(qp, x) -> float:
    """``max_i sum_j |P_ij| |x_j|``: the size of ``P x`` before cancellation, which sets its rounding
    error (an objective constant on the feasible set, e.g. the interactions of a planar robot whose
    cables all lie in its plane, has a gradient of rounding size at every feasible point)."""
    ax = np.abs(x)
    if qp.structured:
        F = np.abs(qp.P_factor)
        return float((np.abs(qp.P_diag) * ax + F.T @ (F @ ax)).max(initial=0.0))
    return float((np.abs(qp.P) @ ax).max(initial=0.0))


def kkt_problems(qp, sol: Solution, settings: Settings = DEFAULT) -> list[str]:
    """What the answer breaks, as messages (empty: it passes; tolerances: ``settings``' acceptance)."""
    s = settings
    r = kkt_residuals(qp, sol, s)
    problems = []
    if not r["eom"] <= s.eom_rel:
        problems.append(f"equation-of-motion residual {r['eom']:.2e} > {s.eom_rel:g}")
    if not r["bound"] <= s.bound_abs:
        problems.append(f"bounds broken by {r['bound']:.2e}")
    if not r["cone_deg"] <= s.cone_deg:
        problems.append(f"a cone broken by {r['cone_deg']:.2e} deg")
    if np.isfinite(r["stationarity"]) or np.isfinite(r["complementarity"]):
        if not r["stationarity"] <= s.kkt_dual_rel:
            problems.append(f"not stationary (relative residual {r['stationarity']:.1e})")
        if not r["complementarity"] <= s.kkt_gap_rel:
            problems.append(f"multipliers inconsistent with the active set (relative gap "
                            f"{r['complementarity']:.1e})")
    return problems


def project_to_bounds(qp, sol: Solution, settings: Settings = DEFAULT) -> Solution:
    """``x`` projected onto the bounds when it misses them by at most ``settings.bound_snap_rel`` (relative):
    iterative back-ends meet bounds to their tolerance, which at forces of 1e6 N is beyond the
    check's absolute 1e-9 N. A larger miss is left for the check to flag."""
    x = sol.x
    if not _outside(x, qp.lb, qp.ub):
        return sol
    slack = settings.bound_snap_rel * (1.0 + np.maximum(np.abs(qp.lb), np.abs(qp.ub)))
    if np.all(x >= qp.lb - slack) and np.all(x <= qp.ub + slack):
        x = np.clip(x, qp.lb, qp.ub)
        return sol.but(x=x, objective=qp.objective(x))
    return sol


def _outside(x, lb, ub) -> bool:
    """Whether ``x`` leaves the bounds anywhere (compiled when the kernels are: one call instead of
    four numpy ones on every instant)."""
    if jit.ready():
        c_ = np.ascontiguousarray
        return bool(jit.kernels("solvers._fast").outside_bounds(c_(x, dtype=float), c_(lb, dtype=float), c_(ub, dtype=float)))
    return bool((x < lb).any() or (x > ub).any())


class Project(Stage):
    """Refining stage: :func:`project_to_bounds`."""

    name = "project"
    refines = True

    def __init__(self, settings: Settings = DEFAULT):
        self.settings = settings

    def run(self, qp, sol, deadline):
        return project_to_bounds(qp, sol, self.settings)


class Check(Stage):
    """Refining stage, last of every chain: an optimal answer that fails :func:`kkt_problems` is
    downgraded to ``inaccurate`` with the reasons in its message (tolerances: ``settings``)."""

    name = "check"
    refines = True

    def __init__(self, settings: Settings = DEFAULT):
        self.settings = settings

    def run(self, qp, sol, deadline):
        if sol.verified:  # checked by the compiled active-set solver, to tighter tolerances
            return sol
        problems = kkt_problems(qp, sol, self.settings)
        if not problems:
            return sol
        note = f"{sol.stage or 'the solver'}'s answer fails the KKT check: " + "; ".join(problems)
        return sol.but(status=INACCURATE, message=f"{sol.message}; {note}" if sol.message else note)


__all__ = ["eom_residual", "kkt_residuals", "kkt_problems", "project_to_bounds", "Project", "Check",
           "OPTIMAL"]
