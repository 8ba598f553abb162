"""The least-norm stage's optimal-face rows (mcdm_pin.solvers.least_norm.optimal_face_rows) split off
the unit rows (diagonal entries of ``P``, strongly active bounds) before the SVD: the basis must be
orthonormal and span exactly the rows' space, checked against an SVD of all the rows stacked."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import nnls

from mcdm_pin import jit

from mcdm_pin.solvers.base import OPTIMAL, Solution
from mcdm_pin.solvers.least_norm import optimal_face_rows

from .test_solvers import _weak_factor_problem


def _span_of_all(qp, sol):
    """An orthonormal basis of every row's span by one SVD (the stage's former computation)."""
    n = qp.n
    rows = [qp.P_factor, np.eye(n)[qp.P_diag != 0], qp.A, qp.c[None, :]]
    near = 1e-8
    at = ((sol.x - qp.lb <= near * (1 + np.abs(qp.lb))) & (sol.z < 0)) | \
         ((qp.ub - sol.x <= near * (1 + np.abs(qp.ub))) & (sol.z > 0))
    rows.append(np.eye(n)[at])
    N = np.vstack(rows)
    N = N[np.linalg.norm(N, axis=1) > 0]
    N = N / np.linalg.norm(N, axis=1)[:, None]
    _, s, Vt = np.linalg.svd(N, full_matrices=False)
    return Vt[s > 1e-10 * s.max()]


@pytest.mark.parametrize("seed", range(4))
def test_face_rows_span_what_one_svd_of_all_rows_spans(seed):
    rng = np.random.default_rng(seed)
    qp = _weak_factor_problem(seed, cone=False)
    n = qp.n
    P_diag = np.where(rng.uniform(size=n) < 0.3, rng.uniform(0.5, 2.0, n), 0.0)
    qp = qp.replace(P_diag=P_diag, P=None)
    # a point with some variables at their bounds, multipliers pushing them there
    x = rng.uniform(1.0, 20.0, n)
    low, up = rng.choice(n, 6, replace=False)[:3], rng.choice(n, 6, replace=False)[3:]
    up = np.setdiff1d(up, low)
    x[low], x[up] = qp.lb[low], qp.ub[up]
    z = np.zeros(n)
    z[low], z[up] = -1.0, 1.0
    sol = Solution(x, OPTIMAL, 0.0, y=np.zeros(len(qp.b)), z=z, z_cone=np.zeros((0, 3)))
    E = optimal_face_rows(qp, sol)
    ref = _span_of_all(qp, sol)
    assert E.shape == ref.shape
    np.testing.assert_allclose(E @ E.T, np.eye(len(E)), atol=1e-12)
    # the same space: each basis is reproduced by projecting it onto the other
    np.testing.assert_allclose(ref @ E.T @ E, ref, atol=1e-10)
    np.testing.assert_allclose(E @ ref.T @ ref, E, atol=1e-10)


@pytest.mark.parametrize("seed", range(2))
def test_face_rows_of_a_dense_objective_span_its_range_and_the_equations(seed):
    # P without a factor: the objective's rows are its eigenvectors of nonzero eigenvalue (no unit
    # rows), so the basis spans range(P) + rows(A) + c, whatever the compiled gathering does
    qp = _weak_factor_problem(seed, cone=False)
    n = qp.n
    rng = np.random.default_rng(seed)
    B = rng.normal(size=(n // 2, n))
    qp = qp.replace(P=B.T @ B)
    E = optimal_face_rows(qp, None)
    N = np.vstack([B, qp.A, qp.c[None, :]])
    N = N / np.linalg.norm(N, axis=1)[:, None]
    _, s, Vt = np.linalg.svd(N, full_matrices=False)
    ref = Vt[s > 1e-10 * s.max()]
    assert E.shape == ref.shape
    np.testing.assert_allclose(E @ E.T, np.eye(len(E)), atol=1e-12)
    np.testing.assert_allclose(ref @ E.T @ E, ref, atol=1e-10)
    np.testing.assert_allclose(E @ ref.T @ ref, E, atol=1e-10)


def _random_face(rng, n=14):
    """A face of ``k`` orthonormal directions over ``m`` of ``n`` coordinates, a point on it within its
    bounds (some at them) and weights."""
    m = int(rng.integers(3, 10))
    k = int(rng.integers(1, min(4, m) + 1))
    rest = np.sort(rng.choice(n, m, replace=False))
    x, w = rng.uniform(0.5, 5.0, n), rng.uniform(0.2, 2.0, n)
    N = np.linalg.qr(rng.standard_normal((m, k)))[0].T.copy()
    lb, ub = np.full(n, -np.inf), np.full(n, np.inf)
    for i in rest:
        if rng.uniform() < 0.7:
            lb[i] = x[i] - rng.uniform(0.0, 1.0) * (rng.uniform() < 0.9)  # a tenth exactly at the bound
        if rng.uniform() < 0.3:
            ub[i] = x[i] + rng.uniform(0.0, 1.0)
    return x, w, rest, N, lb, ub


_NO_CONES = (np.zeros(0, dtype=np.bool_), np.zeros((0, 3, 14)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))


def test_the_faces_least_norm_point_is_optimal_among_its_bounds():
    """``face_least_norm`` on 300 random faces (1-4 directions, 3-9 coordinates, some bounds binding,
    some met exactly at the start): the point lies on the face (``x + N^T t``, the other coordinates
    unmoved), keeps every bound, and satisfies the least-norm problem's KKT conditions: ``N W x``
    (the gradient along the face) is a nonnegative combination of the binding bounds' normals
    (``scipy.optimize.nnls``, residual 1e-10 of its size)."""
    kernel = jit.kernels("solvers._face_qp").face_least_norm
    rng = np.random.default_rng(1)
    binding = 0
    for _ in range(300):
        x, w, rest, N, lb, ub = _random_face(rng)
        xf, direct, steps = kernel(x, w, rest, N, lb, ub, *_NO_CONES)
        assert direct and steps >= 1
        others = np.setdiff1d(np.arange(len(x)), rest)
        assert np.array_equal(xf[others], x[others])
        t = np.linalg.lstsq(N.T, xf[rest] - x[rest], rcond=None)[0]
        np.testing.assert_allclose(N.T @ t, xf[rest] - x[rest], atol=1e-12)
        assert np.all(xf >= lb) and np.all(xf <= ub)
        at_lb, at_ub = xf[rest] == lb[rest], xf[rest] == ub[rest]
        C = np.hstack([N[:, at_lb], -N[:, at_ub]])  # the binding bounds' inward normals, over t
        grad = N @ (w[rest] * xf[rest])
        lam, res = nnls(C, grad) if C.shape[1] else (None, np.linalg.norm(grad))
        assert res <= 1e-10 * max(np.linalg.norm(N @ (w[rest] * x[rest])), 1.0)
        binding += int(C.shape[1] > 0)
    assert binding > 150  # most faces have a bound that binds


def test_the_faces_least_norm_point_answers_only_where_its_cones_hold():
    """A cone not held on the face is an inequality the face's problem leaves out: the point
    answers where it meets the cone, not where it breaks it; with no free direction the face is
    its one point."""
    kernel = jit.kernels("solvers._face_qp").face_least_norm
    rng = np.random.default_rng(3)
    x, w, rest, N, lb, ub = _random_face(rng)
    lb[:] = -np.inf
    ub[:] = np.inf
    n = len(x)
    xf, direct, _ = kernel(x, w, rest, N, lb, ub, *_NO_CONES)
    assert direct
    G = np.zeros((1, 3, n))
    G[0, 2, rest[0]] = np.sign(xf[rest[0]])  # the cone's axial force: |x_rest[0]| at the point; its side force: 0.1
    gc, ax = np.array([[0.1, 0.0, 0.0]]), np.array([[0.0, 0.0, 1.0]])
    not_held = np.zeros(1, dtype=np.bool_)
    wide = np.array([0.2 / max(abs(xf[rest[0]]), 1e-9)])  # 0.1 <= tan * F_z at the point, with a margin of 2
    assert kernel(x, w, rest, N, lb, ub, not_held, G, gc, ax, wide)[1]
    assert not kernel(x, w, rest, N, lb, ub, not_held, G, gc, ax, 0.25 * wide)[1]
    held = np.ones(1, dtype=np.bool_)  # held: its rows are the face's, not an inequality
    assert kernel(x, w, rest, N, lb, ub, held, G, gc, ax, 0.25 * wide)[1]
    xf0, direct0, steps0 = kernel(x, w, rest, np.zeros((0, len(rest))), lb, ub, *_NO_CONES)
    assert direct0 and steps0 == 0 and np.array_equal(xf0, x)
