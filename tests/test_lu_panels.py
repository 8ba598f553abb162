"""The small dense LU of the compiled solvers (mcdm_pin/solvers/_kkt_linalg.py, ``lu_factor``) works in
panels of four columns; its factors must be those of plain column-by-column elimination to the bit
(the same operations on every entry in the same order, a zero multiplier's update skipped, a zero's
sign kept), so that no answer moves. Checked compiled against the column-by-column elimination
compiled here with the same flags, and uncompiled against the same elimination run as Python, on
dense matrices of every panel remainder and on KKT systems with zero blocks, exact and signed
zeros and pivoting."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import jit


def _columns(R):
    """Column-by-column elimination with partial pivoting (the reference): the first largest
    pivot candidate, whole rows swapped, each row below less its multiple of the pivot row (a zero
    multiplier's row left as it is)."""
    n = R.shape[0]
    M = R.copy()
    perm = np.arange(n)
    for k in range(n):
        p = k + int(np.argmax(np.abs(M[k:, k])))
        big = abs(M[p, k])
        if not (big > 0.0 and np.isfinite(big)):
            return M, perm, False
        row = M[k].copy()
        M[k], M[p] = M[p], row
        perm[k], perm[p] = perm[p], perm[k]
        for i in range(k + 1, n):
            l = M[i, k] * (1.0 / M[k, k])
            M[i, k] = l
            if l != 0.0:
                for j in range(k + 1, n):
                    M[i, j] += -l * M[k, j]
    return M, perm, True


def _matrices():
    rng = np.random.default_rng(11)
    out = []
    for n in (1, 2, 3, 4, 5, 7, 8, 9, 13, 30, 59, 61, 62, 63, 100):
        out.append(rng.normal(size=(n, n)) * 10.0 ** rng.uniform(-3, 3, (1, n)))
    for nf, m in ((6, 3), (31, 28), (40, 24), (70, 45)):  # [[H, A^T], [A, 0]]: zero blocks, zero multipliers
        F = rng.normal(size=(nf // 2, nf))
        A = rng.normal(size=(m, nf))
        A[rng.random(A.shape) < 0.6] = 0.0
        A[A == 0.0] *= -1.0  # (signed zeros: -0.0 where the entry is zero)
        K = np.zeros((nf + m, nf + m))
        K[:nf, :nf] = F.T @ F + np.diag(rng.uniform(0.0, 1e-3, nf))
        K[:nf, nf:], K[nf:, :nf] = A.T, A
        out.append(K)
    out.append(np.diag([0.0, 1.0, 2.0]))  # a zero pivot: refused
    return out


@pytest.mark.parametrize("compiled", [True, False])
def test_the_panels_give_column_eliminations_factors_to_the_bit(monkeypatch, compiled):
    if compiled:
        numba = pytest.importorskip("numba")
        jit.prepare(policy="wait")
        reference = numba.njit(fastmath={"reassoc", "contract"})(_columns)
    else:
        monkeypatch.setattr(jit, "_COMPILED", False)
        reference = _columns
    lu = jit.kernels("solvers._kkt_linalg").lu_factor
    refused = 0
    for R in _matrices():
        M, perm, ok = lu(R)
        M0, perm0, ok0 = reference(R)
        assert ok == ok0
        if not ok:
            refused += 1
            continue
        np.testing.assert_array_equal(perm, perm0)
        np.testing.assert_array_equal(M, M0)
        np.testing.assert_array_equal(np.signbit(M), np.signbit(M0))
        n = len(R)
        L, U = np.tril(M, -1) + np.eye(n), np.triu(M)
        assert np.abs(R[perm] - L @ U).max() <= 1e-12 * max(1.0, np.abs(R).max())
    assert refused == 1
