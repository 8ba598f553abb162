r"""Margins of an instant as functions of the assembled problem (a :class:`~mcdm_pin.qp.QPData`):
how far the force limit or the cones would have to move for it to be feasible, or how much room a
feasible instant has. Each costs a few cold cone-program solves (Clarabel, on the scaled problem),
whatever the answer, feasible or not.

:func:`needed_f_max`
    The smallest common upper bound ``t`` on the chosen variables (default: every variable with a
    finite upper bound, i.e. every cable) for which the instant is feasible, with every other
    constraint kept (lower bounds, the other variables' upper bounds, the cones): one convex program,

    .. math:: \min_{x, t}\ t \quad\text{s.t.}\quad A x = b,\ l \le x,\ x_i \le t\ (i \in S),\
              x_j \le u_j\ (j \notin S),\ \text{cones}.

    ``inf`` when no ``t`` would do (a cable would have to push, or a cone cannot be met at all).

:func:`needed_cone_deg`
    The smallest common half-angle ``rho`` of the chosen cones (default: all) for which the instant
    is feasible, the other constraints kept:
    :math:`\tan\rho^* = \min_x \max_k \|F_{k,\perp}(x)\| / a_k^T F_k(x)`, a generalized fractional
    program, solved by the Dinkelbach-type method of Crouzeix, Ferland and Schaible (1985, "An
    algorithm for generalized fractional programs", JOTA 47): with :math:`\tau_j` the current ratio,
    solve the cone program

    .. math:: \min_{x,\sigma}\ \sigma \quad\text{s.t.}\quad
              \|F_{k,\perp}(x)\| \le \tau_j\, a_k^T F_k(x) + \sigma\, a_k^T F_k(x_j)\ \ \forall k,\
              \text{the other constraints},

    and set :math:`\tau_{j+1} = \max_k \|F_{k,\perp}(x_{j+1})\| / a_k^T F_k(x_{j+1})`; it stops when the
    optimal ``sigma`` reaches 0 (then :math:`\tau_j` is optimal). The ratios fall monotonically and
    converge superlinearly: 3-6 solves where a bisection to 1e-4 degrees took ~20. ``90`` (degrees)
    means only a half-space would do (``inf`` when not even that).

Both return a number for feasible instants too (then at most the current limit): the workspace's
margins.
"""

from __future__ import annotations

import numpy as np

from ..settings import DEFAULT, Settings
from ..exceptions import SolverError


def _clarabel(c, A_eq, b_eq, G, h, soc):
    """``min c^T v`` s.t. ``A_eq v = b_eq``, ``G v <= h``, ``soc``: list of ``(S (3, nv), s (3,))`` with
    ``S v + s`` in the second-order cone. Returns ``(v, status)``."""
    import clarabel
    from scipy import sparse

    nv = len(c)
    blocks, rhs, cones = [], [], []
    if len(b_eq):
        blocks.append(A_eq)
        rhs.append(b_eq)
        cones.append(clarabel.ZeroConeT(len(b_eq)))
    if len(h):
        blocks.append(G)
        rhs.append(h)
        cones.append(clarabel.NonnegativeConeT(len(h)))
    for S, s in soc:
        blocks.append(-S)
        rhs.append(s)
        cones.append(clarabel.SecondOrderConeT(3))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-10
    solver = clarabel.DefaultSolver(sparse.csc_matrix((nv, nv)), np.asarray(c, dtype=float),
                                    sparse.csc_matrix(np.vstack(blocks)), np.concatenate(rhs), cones, settings)
    sol = solver.solve()
    return np.array(sol.x), str(sol.status)


def _scaled(qp):
    from ..scaling import apply_scaling, scaling_factors

    s = scaling_factors(qp, force=True)
    return apply_scaling(qp, s), s


def _box_rows(qp, nv, skip=()):
    """Rows ``G v <= h`` of the finite bounds of x (v = [x; extra]), except the upper bounds in ``skip``."""
    n = qp.n
    eye = np.eye(n, nv)
    hi = [i for i in np.flatnonzero(np.isfinite(qp.ub)) if i not in set(skip)]
    lo = np.flatnonzero(np.isfinite(qp.lb))
    return np.vstack([eye[hi], -eye[lo]]), np.concatenate([qp.ub[hi], -qp.lb[lo]])


def _cone_socs(qp, nv, which):
    T, t = qp.cone_rows()
    out = []
    for k in which:
        S = np.zeros((3, nv))
        S[:, :qp.n] = T[k]
        out.append((S, t[k]))
    return out


def needed_f_max(qp, variables=None) -> float:
    """The smallest common upper bound on ``variables`` (indices; default: those with a finite upper
    bound) that makes ``qp`` feasible (module docstring); same unit as the bounds."""
    n = qp.n
    sel = np.flatnonzero(np.isfinite(qp.ub)) if variables is None else np.asarray(variables, dtype=int)
    if not len(sel):
        raise SolverError("needed_f_max: no variable to bound")
    sq, s = _scaled(qp)
    d = s.d
    unit = float(d[sel].max())
    nv = n + 1
    G, h = _box_rows(sq, nv, skip=sel)
    rows = np.zeros((len(sel), nv))
    rows[np.arange(len(sel)), sel] = d[sel] / unit  # d_i x_i <= t = unit * t_s
    rows[:, n] = -1.0
    lo = float(np.max(qp.lb[sel], initial=0.0)) / unit  # t at least every lower bound
    floor = np.zeros((1, nv))
    floor[0, n] = -1.0
    G, h = np.vstack([G, rows, floor]), np.concatenate([h, np.zeros(len(sel)), [-lo]])
    A = np.hstack([sq.A, np.zeros((sq.A.shape[0], 1))])
    c = np.zeros(nv)
    c[n] = 1.0
    v, status = _clarabel(c, A, sq.b, G, h, _cone_socs(sq, nv, range(len(sq.cones))))
    if status in ("Solved", "AlmostSolved"):
        return float(v[n] * unit)
    if status in ("PrimalInfeasible", "AlmostPrimalInfeasible", "DualInfeasible", "AlmostDualInfeasible"):
        return float("inf")
    raise SolverError(f"needed_f_max: Clarabel ended with {status}")


def _ratios(qp, x, which):
    G, g, ax, _, _ = qp.cone_arrays()
    F = g[which] + G[which] @ x
    along = np.einsum("ka,ka->k", ax[which], F)
    perp = np.linalg.norm(F - along[:, None] * ax[which], axis=1)
    return perp, along


def needed_cone_deg(qp, cones=None, max_solves: int = 30, settings: Settings = DEFAULT) -> float:
    """The smallest common half-angle (degrees) of ``cones`` (indices into ``qp.cones`` or joint
    names; default: all) that makes ``qp`` feasible (module docstring)."""
    if not qp.cones:
        raise SolverError("needed_cone_deg: the problem has no cones")
    names = [c.joint for c in qp.cones]
    if cones is None:
        which = list(range(len(qp.cones)))
    else:
        which = [names.index(c) if isinstance(c, str) else int(c) for c in cones]
    others = [k for k in range(len(qp.cones)) if k not in which]
    sq, _ = _scaled(qp)
    n = qp.n
    G_all, g_all, ax, _, _ = sq.cone_arrays()
    # a start where every chosen cone's force points into its half-space, as far as possible:
    # max s  s.t.  a_k . F_k >= s (the other constraints kept)
    nv = n + 1
    Gb, hb = _box_rows(sq, nv)
    half = np.zeros((len(which), nv))
    for r, k in enumerate(which):
        half[r, :n] = -(ax[k] @ G_all[k])
        half[r, n] = 1.0
    hh = np.array([ax[k] @ g_all[k] for k in which])
    cap = np.zeros((1, nv))
    cap[0, n] = 1.0
    A = np.hstack([sq.A, np.zeros((sq.A.shape[0], 1))])
    c = np.zeros(nv)
    c[n] = -1.0
    v, status = _clarabel(c, A, sq.b, np.vstack([Gb, half, cap]), np.concatenate([hb, hh, [1.0]]),
                          _cone_socs(sq, nv, others))
    if status not in ("Solved", "AlmostSolved"):
        return float("inf")
    if not v[n] > 0:
        return 90.0 if v[n] >= -1e-12 else float("inf")
    x = v[:n]
    perp, along = _ratios(sq, x, which)
    tau = float((perp / along).max())
    for _ in range(max_solves):
        D = along  # the normalisation a_k . F_k(x_j) > 0
        socs = _cone_socs(sq, nv, others)
        for r, k in enumerate(which):
            S = np.zeros((3, nv))
            S[0, :n] = tau * (ax[k] @ G_all[k])
            S[0, n] = D[r]
            B = np.vstack([sq.cones[k].basis])  # (2, 3)
            S[1:, :n] = B @ G_all[k]
            socs.append((S, np.concatenate([[tau * (ax[k] @ g_all[k])], B @ g_all[k]])))
        sigma_floor = np.zeros((1, nv))
        sigma_floor[0, n] = -1.0
        v, status = _clarabel(np.eye(nv)[n], A, sq.b, np.vstack([Gb, sigma_floor]),
                              np.concatenate([hb, [tau + 1.0]]), socs)
        if status not in ("Solved", "AlmostSolved"):
            break
        x_new = v[:n]
        perp, along = _ratios(sq, x_new, which)
        if not np.all(along > 0):
            break
        tau_new = float((perp / along).max())
        if v[n] >= -settings.margin_rel * max(tau, 1e-12) or tau_new >= tau * (1.0 - settings.margin_rel):
            tau = min(tau, tau_new)
            break
        x, tau = x_new, tau_new
    return float(np.degrees(np.arctan(tau)))


__all__ = ["needed_f_max", "needed_cone_deg"]
