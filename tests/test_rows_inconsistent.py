"""A singular KKT system whose rows are inconsistent is rejected without an SVD
(mcdm_pin/solvers/_kkt_linalg.py, ``rows_inconsistent``): the rows' least-squares point, from a
Cholesky of ``R^T R`` that drops dependent columns, must reject only systems that least squares
(``lstsq_solve``) also rejects, never a consistent one, and must catch the inconsistent ones least
squares rejects, compiled and uncompiled alike (the 96-DoF chain's cold instants that met it:
docs/speed.md)."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def linalg(kernel_modules):
    return kernel_modules("solvers._kkt_linalg")


def _systems(seed, count, big=40):
    """Random KKT systems ``[[H, R^T], [R, 0]]`` with rank-deficient rows ``R``, their right-hand
    sides consistent with the rows (``r_c = R x``) or not (random), scaled over six decades."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        nf, m = int(rng.integers(3, big)), int(rng.integers(1, big))
        rank = int(rng.integers(1, min(nf, m) + 1))
        scale = 10 ** rng.uniform(-3, 3)
        R = rng.standard_normal((m, rank)) @ rng.standard_normal((rank, nf)) * scale
        H = rng.standard_normal((nf, nf))
        K = np.zeros((nf + m, nf + m))
        K[:nf, :nf], K[:nf, nf:], K[nf:, :nf] = H @ H.T, R.T, R
        consistent = bool(rng.random() < 0.5)
        rc = R @ rng.standard_normal(nf) if consistent else rng.standard_normal(m) * 10 ** rng.uniform(-6, 3)
        yield K, np.concatenate([rng.standard_normal(nf), rc]), nf, consistent


def test_rejects_what_least_squares_rejects_and_nothing_else(linalg):
    rejected = failed = 0
    for K, rhs, nf, consistent in _systems(0, 400):
        verdict = linalg.rows_inconsistent(K, rhs, nf)
        lstsq_fails = not np.all(np.isfinite(linalg.lstsq_solve(K, rhs)))
        assert not (verdict and consistent)
        assert not (verdict and not lstsq_fails)
        rejected += verdict
        failed += lstsq_fails
    assert failed > 100  # the sample has inconsistent systems
    assert rejected >= failed - 2  # and they are caught without the SVD (borderline ones go on to it)


def test_full_rank_rows_and_no_rows_are_consistent(linalg):
    rng = np.random.default_rng(3)
    nf, m = 12, 5
    R = rng.standard_normal((m, nf))
    K = np.zeros((nf + m, nf + m))
    K[:nf, :nf], K[:nf, nf:], K[nf:, :nf] = np.eye(nf), R.T, R
    assert not linalg.rows_inconsistent(K, rng.standard_normal(nf + m), nf)
    assert not linalg.rows_inconsistent(np.eye(4), np.ones(4), 4)


def test_a_singular_inconsistent_system_gives_nans_and_a_consistent_one_its_solution(linalg):
    rng = np.random.default_rng(5)
    nf = 6
    R = rng.standard_normal((3, nf))
    R = np.vstack([R, R[0] + R[1]])  # a dependent row
    K = np.zeros((nf + 4, nf + 4))
    K[:nf, :nf], K[:nf, nf:], K[nf:, :nf] = np.eye(nf), R.T, R
    x = rng.standard_normal(nf)
    rhs = np.concatenate([rng.standard_normal(nf), R @ x])
    sol = linalg.kkt_solve(K, rhs, nf, False)  # (False: least squares, as where the LU fails)
    assert np.all(np.isfinite(sol))
    np.testing.assert_allclose(K @ sol, rhs, atol=1e-10)
    rhs[-1] += 1.0  # the dependent row now contradicts the two it depends on
    assert linalg.rows_inconsistent(K, rhs, nf)
    assert np.all(np.isnan(linalg.kkt_solve(K, rhs, nf, False)))
    # more rows than unknowns, two columns alike (determined_solve's Cholesky fails on them)
    nf, m = 3, 5
    R = rng.standard_normal((m, nf))
    R[:, 2] = R[:, 1]
    K = np.zeros((nf + m, nf + m))
    K[:nf, :nf], K[:nf, nf:], K[nf:, :nf] = np.eye(nf), R.T, R
    rhs = np.concatenate([np.ones(nf), R @ np.array([1.0, 2.0, -1.0])])
    assert not linalg.rows_inconsistent(K, rhs, nf)
    assert np.all(np.isfinite(linalg.determined_solve(K, rhs, nf)))
    rhs[-1] += 1e-3
    assert linalg.rows_inconsistent(K, rhs, nf)
    assert np.all(np.isnan(linalg.determined_solve(K, rhs, nf)))
