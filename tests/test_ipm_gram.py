"""The interior-point method's Gram product ``B D^-1 B^T`` through :func:`gram_plan`
(mcdm_pin/solvers/_ipm_newton.py): the columns with two nonzero entries or more go through the dense
product, a column with one entry adds to its row's diagonal entry, a zero column adds nothing. It
must give the dense product, and where every column has several entries read ``B`` itself. The
kernels run here as their Python code, so nothing compiles."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import jit


@pytest.fixture
def newton(monkeypatch):
    monkeypatch.setattr(jit, "_COMPILED", False)
    return jit.kernels("solvers._ipm_newton")


def _rows(rng, rb, n, zero=(), single=()):
    """``rb`` rows over ``n`` variables, padded with zero columns to a multiple of 8 (as the method's
    ``B`` is), with the columns ``zero`` empty and each column of ``single`` holding one entry."""
    B = np.zeros((rb, (n + 7) // 8 * 8))
    B[:, :n] = rng.normal(size=(rb, n))
    B[:, list(zero)] = 0.0
    for t in single:
        keep = rng.integers(rb)
        B[:, t] = 0.0
        B[keep, t] = rng.normal()
    return B


@pytest.mark.parametrize("rb, n, zero, single", [(5, 12, (3,), (5, 7)), (75, 85, (), tuple(range(63, 85))),
                                                 (9, 10, (0, 9), ())])
def test_the_gram_product_of_the_plan_is_the_dense_one(newton, rb, n, zero, single):
    rng = np.random.default_rng(rb + n)
    B = _rows(rng, rb, n, zero, single)
    plan = newton.gram_plan(B, n)
    Bg, cols, srow, scol, sval = plan
    assert sorted(scol.tolist()) == sorted(single)
    assert set(cols.tolist()) == set(range(n)) - set(zero) - set(single)
    assert Bg.shape[1] % 8 == 0 and Bg.shape[1] >= len(cols)
    dinv = rng.uniform(1e-3, 1e3, n)
    Km = np.full((rb, rb), np.nan)
    newton._gram(plan, dinv, np.full((2, B.shape[1]), np.nan), Km)
    ref = (B[:, :n] * dinv) @ B[:, :n].T
    low = np.tril_indices(rb)
    np.testing.assert_allclose(Km[low], ref[low], rtol=0, atol=1e-13 * np.abs(ref).max())


def test_the_plan_reads_b_itself_where_every_column_has_several_entries(newton):
    B = _rows(np.random.default_rng(3), 6, 11)
    Bg, cols, srow, _, _ = newton.gram_plan(B, 11)
    assert Bg is B and cols.tolist() == list(range(11)) and len(srow) == 0
