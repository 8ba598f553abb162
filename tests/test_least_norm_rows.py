"""The least-norm stage's optimal-face rows (mcdm_pin.solvers.least_norm.optimal_face_rows) split off
the unit rows (diagonal entries of ``P``, strongly active bounds) before the SVD: the basis must be
orthonormal and span exactly the rows' space, checked against an SVD of all the rows stacked."""

from __future__ import annotations

import numpy as np
import pytest

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


def test_the_faces_least_norm_point_solves_the_weighted_projection():
    """``_face_least_norm``: ``x + N^T t`` with ``t`` minimising ``sum_i w_i x_i^2`` (the weighted
    projection onto the face, checked by its normal equations); ``False`` where a bound of ``rest``
    is broken there or a cone is not held; a face of one point (no free direction) is ``x``."""
    kernel = jit.kernels("solvers._unique")._face_least_norm
    rng = np.random.default_rng(3)
    n, rest = 9, np.array([1, 2, 4, 5, 7])
    x, w = rng.uniform(1.0, 5.0, n), rng.uniform(0.5, 2.0, n)
    N = np.linalg.qr(rng.standard_normal((len(rest), 2)))[0].T.copy()  # two orthonormal directions
    lb, ub = np.full(n, -np.inf), np.full(n, np.inf)
    held = np.ones(1, dtype=np.bool_)
    xf, direct = kernel(x, w, rest, N, lb, ub, held)
    assert direct
    d = xf - x
    assert np.all(d[np.setdiff1d(np.arange(n), rest)] == 0.0)
    t = np.linalg.lstsq(N.T, d[rest], rcond=None)[0]
    np.testing.assert_allclose(N.T @ t, d[rest], atol=1e-12)  # a move along the face
    np.testing.assert_allclose(N @ (w[rest] * xf[rest]), 0.0, atol=1e-12)  # the normal equations
    lb2 = lb.copy()
    lb2[rest[0]] = xf[rest[0]] + 1e-9  # a bound that the projection breaks
    assert not kernel(x, w, rest, N, lb2, ub, held)[1]
    assert not kernel(x, w, rest, N, lb, ub, np.array([True, False]))[1]  # a cone not held
    xf0, direct0 = kernel(x, w, rest, np.zeros((0, len(rest))), lb, ub, held)
    assert direct0 and np.array_equal(xf0, x)
