"""The active-set solver's KKT solve through the Schur complement of its rows, where the free
variables' block is diagonal (mcdm_pin/solvers/_kkt_linalg.py, ``schur_solve``). It must give a
dense solve's solution. Dependent rows must give a solution when they are consistent and NaN when
not, as the least-squares solve it replaces did. It must refuse the cases the caller's LU then
solves: a block that is not diagonal, a negligible diagonal entry. The kernels run here as their
Python code, so nothing compiles."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import jit


def _kkt(rng, nf, m, d):
    """``[[diag(d), C^T], [C, 0]]`` with a random ``C`` (m x nf)."""
    C = rng.normal(size=(m, nf))
    K = np.zeros((nf + m, nf + m))
    K[:nf, :nf] = np.diag(d)
    K[:nf, nf:], K[nf:, :nf] = C.T, C
    return K


@pytest.fixture
def linalg(monkeypatch):
    monkeypatch.setattr(jit, "_COMPILED", False)
    return jit.kernels("solvers._kkt_linalg")


@pytest.mark.parametrize("nf, m", [(5, 2), (40, 12), (120, 30)])
def test_the_schur_complement_solves_a_diagonal_kkt_system_as_a_dense_solve_does(linalg, nf, m):
    rng = np.random.default_rng(nf)
    K = _kkt(rng, nf, m, rng.uniform(0.5, 2.0, nf))
    rhs = rng.normal(size=nf + m)
    x, ok = linalg.schur_solve(K, rhs, nf)
    assert ok
    ref = np.linalg.solve(K, rhs)
    np.testing.assert_allclose(x, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    assert np.abs(K @ x - rhs).max() <= 1e-13 * max(np.abs(K).max() * np.abs(x).max(), np.abs(rhs).max())


def test_the_schur_complement_refuses_what_it_cannot_solve_exactly(linalg):
    rng = np.random.default_rng(7)
    nf, m = 20, 6
    K = _kkt(rng, nf, m, rng.uniform(0.5, 2.0, nf))
    rhs = rng.normal(size=nf + m)
    coupled = K.copy()
    coupled[0, 1] = coupled[1, 0] = 0.1  # a held cone's curvature: not diagonal
    negligible = K.copy()
    negligible[3, 3] = 1e-9 * K[:nf, :nf].max()  # a Tikhonov term only: S would carry 1e9
    for bad in (coupled, negligible):
        assert not linalg.schur_solve(bad, rhs, nf)[1]


def test_dependent_rows_solve_when_consistent_and_give_nan_when_not(linalg):
    rng = np.random.default_rng(11)
    nf, m = 20, 6
    K = _kkt(rng, nf, m, rng.uniform(0.5, 2.0, nf))
    K[nf + 1, :nf] = K[:nf, nf + 1] = 2.0 * K[nf, :nf]  # a row twice
    rhs = rng.normal(size=nf + m)
    rhs[nf + 1] = 2.0 * rhs[nf]  # consistent
    x, ok = linalg.schur_solve(K, rhs, nf)
    assert ok and np.abs(K @ x - rhs).max() <= 1e-12 * np.abs(rhs).max()
    ref = np.linalg.lstsq(K, rhs, rcond=None)[0]  # the forces are unique, the multipliers not
    np.testing.assert_allclose(x[:nf], ref[:nf], rtol=0, atol=1e-12 * np.abs(ref[:nf]).max())
    rhs[nf + 1] += 1.0  # inconsistent
    x, ok = linalg.schur_solve(K, rhs, nf)
    assert ok and np.isnan(x).all()
