r"""The compiled closed loops (:mod:`mcdm_pin.osim.constraints`): the factorisation of ``G N``, the loop
force's maps at one instant, and the joint wrenches' map ``W``, each one call instead of a dozen small
numpy operations; and :func:`loop_terms`, all of them and what they add to an instant's terms in one
call.

Compiled by ``mcdm-pin compile`` with the other kernels and cached on disk (``cache=True``),
registered with :mod:`mcdm_pin.jit`; until then the same code runs as Python
(``jit.kernels("osim.loop_kernels").loop_instant``). No ``fastmath``.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ..model.kernel_structs import LoopTables, LoopTerms


@njit(cache=True, nogil=True)
def loop_jacobian(J, fp, pt_frame, pt_sign, pt_loop, pt_cols, k):
    """(k, nv) ``G = J_2 - J_1``: per loop point (frame ``pt_frame``, sign ``pt_sign``: + at ``p_2``,
    - at ``p_1``, loop ``pt_loop``) the linear rows of its frame Jacobian in world axes, ``v + w x p``
    from the world Jacobian ``J`` (6, nv: Pinocchio's ``data.J``, ``[v; w]`` at the origin) in the
    columns that move the point (``pt_cols`` (points, nv): 1 in its joint's support, else 0) at the
    point ``p = fp[frame]``."""
    nv = J.shape[1]
    G = np.zeros((k, nv))
    for e in range(pt_frame.shape[0]):
        p0, p1, p2 = fp[pt_frame[e], 0], fp[pt_frame[e], 1], fp[pt_frame[e], 2]
        row, sg = 3 * pt_loop[e], pt_sign[e]
        for c in range(nv):
            if pt_cols[e, c]:
                w0, w1, w2 = J[3, c], J[4, c], J[5, c]
                G[row, c] += sg * (J[0, c] + w1 * p2 - w2 * p1)
                G[row + 1, c] += sg * (J[1, c] + w2 * p0 - w0 * p2)
                G[row + 2, c] += sg * (J[2, c] + w0 * p1 - w1 * p0)
    return G


@njit(cache=True, nogil=True)
def loop_factor(GN, k):
    """One SVD ``G N = U diag(s) V^T`` (``GN`` (k, n), full rank expected): ``(s, K, pinv)`` with ``K``
    the last ``n - k`` columns of ``V`` (an orthonormal basis of ``G N``'s null space) and
    ``pinv = U diag(1/s) V_{:k}^T = (N^T G^T)^+`` (k, n). The caller checks the rank from ``s``."""
    U, s, Vt = np.linalg.svd(GN)
    pinv = (U / s) @ np.ascontiguousarray(Vt[:k])  # (a row slice is typed 'A': BLAS wants 'C')
    return s, np.ascontiguousarray(Vt[k:].T), pinv


@njit(cache=True, nogil=True)
def loop_instant(G, N, tau0, L, S, k):
    """:meth:`mcdm_pin.osim.constraints.PointLoops.instant`'s maps from ``G`` (k, nv), the couplings'
    basis ``N`` (nv, n), ``tau0`` (nv,), ``L`` (m, nv) and the actuators ``S`` (nv, n_act; ``n_act``
    may be 0): ``(s, N K, lambda_0, Lambda, Lambda_act)`` with ``lambda = lambda_0 + Lambda f +
    Lambda_act tau_act`` the least-squares solution of ``N^T G^T lambda = N^T (tau0 + L^T f - S
    tau_act)``."""
    s, K, pinv = loop_factor(G @ N, k)
    lam0 = pinv @ (tau0 @ N)
    Lam = pinv @ np.ascontiguousarray((L @ N).T)
    Lam_act = pinv @ np.ascontiguousarray((-(S.T @ N)).T) if S.shape[1] else np.zeros((k, 0))
    return s, N @ K, lam0, Lam, Lam_act


@njit(cache=True, nogil=True)
def loop_wrench_map(oR, op, fp, pair_joint, pair_frame, pair_sign, pair_loop, njoints, k):
    """(njoints, 6, k) ``W``: for each (loop point, joint whose subtree holds it) pair, minus the
    point's unit forces (world axes, signed: ``+`` on body 2, ``-`` on body 1) moved to the joint,
    in the joint's axes: ``-s [R^T e_c; R^T (r x e_c)]`` in the loop's column ``c`` (``R`` the joint's
    rotation ``oR`` (njoints, 3, 3), ``r`` the point ``fp`` (nframes, 3) minus the joint's origin
    ``op`` (njoints, 3))."""
    W = np.zeros((njoints, 6, k))
    for n in range(pair_joint.shape[0]):
        j, fr, col = pair_joint[n], pair_frame[n], 3 * pair_loop[n]
        sg = -pair_sign[n]
        r0, r1, r2 = fp[fr, 0] - op[j, 0], fp[fr, 1] - op[j, 1], fp[fr, 2] - op[j, 2]
        for c in range(3):
            # r x e_c (world), then both vectors to the joint's axes (R^T x: x's components on R's columns)
            m0 = (0.0, -r2, r1)[c]
            m1 = (r2, 0.0, -r0)[c]
            m2 = (-r1, r0, 0.0)[c]
            for i in range(3):
                W[j, i, col + c] += sg * oR[j, c, i]
                W[j, 3 + i, col + c] += sg * (oR[j, 0, i] * m0 + oR[j, 1, i] * m1 + oR[j, 2, i] * m2)
    return W


@njit(cache=True, nogil=True)
def loop_terms(J, fp, oR, op, tables, N, tau0, L, S, u, RT, child):
    """Everything the closed loops add at one instant, in one call (:class:`LoopTerms`): ``G``
    (:func:`loop_jacobian` from ``J``, ``fp``), the basis and the loop force's maps
    (:func:`loop_instant` with ``N``, ``tau0`` (nv,), ``L`` (m, nv), ``S`` (nv, n_act)), ``W``
    (:func:`loop_wrench_map` from ``oR``, ``op``), then for each physical joint (its Pinocchio joint
    ``child[j]``) its wrenches ``u[j] + W lam0`` and ``RT[j] + W Lam`` and the actuators' share
    ``W Lam_act``, and the equation of motion in the basis. ``tables``: :class:`LoopTables`."""
    tables = LoopTables(*tables)  # (a plain tuple at the boundary: solvers._structs)
    t = tables
    G = loop_jacobian(J, fp, t.pt_frame, t.pt_sign, t.pt_loop, t.pt_cols, t.k)
    s, NK, lam0, Lam, Lam_act = loop_instant(G, N, tau0, L, S, t.k)
    W = loop_wrench_map(oR, op, fp, t.pair_joint, t.pair_frame, t.pair_sign, t.pair_loop, t.njoints, t.k)
    nc, m, na = child.shape[0], L.shape[0], S.shape[1]
    u_out, RT_out, RT_act = np.empty((nc, 6)), np.empty((nc, 6, m)), np.zeros((nc, 6, na))
    for j in range(nc):
        w = np.ascontiguousarray(W[child[j]])  # (6, k)
        u_out[j] = u[j] + w @ lam0
        RT_out[j] = RT[j] + w @ Lam
        if na:
            RT_act[j] = w @ Lam_act
    actuation = NK.T @ S if na else np.zeros((NK.shape[1], 0))
    return LoopTerms(s, NK, lam0, Lam, Lam_act, W, u_out, RT_out, RT_act, actuation, L @ NK, NK.T @ tau0)


def warm_calls():
    """This module's kernels with example arguments of the types the library passes (the placements
    as the strided views :func:`mcdm_pin.model.placements.stacked_view` makes; registered with
    :mod:`mcdm_pin.jit`)."""
    z = np.zeros
    i64 = np.int64
    oM = z((2, 4, 4))
    oR, op = oM[:, :3, :3], oM[:, :3, 3]
    oR.flags.writeable = op.flags.writeable = False
    G = np.eye(3, 4)
    identity = np.eye(4)  # N without couplings: PointLoops' read-only identity
    identity.flags.writeable = False
    tables = LoopTables(z(1, dtype=i64), z(1), z(1, dtype=i64), np.ones((1, 4), dtype=np.bool_), z(1, dtype=i64),
                        z(1, dtype=i64), z(1), z(1, dtype=i64), 2, 3)
    return [(loop_jacobian, (np.asfortranarray(z((6, 4))), op, z(1, dtype=i64), z(1), z(1, dtype=i64),
                             np.ones((1, 4), dtype=np.bool_), 3)),
            (loop_factor, (G, 3)),
            (loop_instant, (G, np.eye(4), z(4), z((2, 4)), z((4, 0)), 3)),
            (loop_instant, (G, np.eye(4), z(4), z((2, 4)), z((4, 1)), 3)),
            (loop_instant, (G, identity, z(4), z((2, 4)), z((4, 0)), 3)),
            (loop_instant, (G, identity, z(4), z((2, 4)), z((4, 1)), 3)),
            (loop_wrench_map, (oR, op, op, z(1, dtype=i64), z(1, dtype=i64), z(1), z(1, dtype=i64), 2, 3))] + [
        (loop_terms, (np.asfortranarray(z((6, 4))), op, oR, op, tuple(tables), basis, z(4), z((2, 4)), z((4, n_act)),
                      z((1, 6)), z((1, 6, 2)), np.ones(1, dtype=i64)))
        for basis in (np.eye(4), identity) for n_act in (0, 1)]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.osim.loop_kernels", warm_calls)


_register()
