"""Coupled coordinates: the basis ``N = dq/dz`` against central finite differences of the couplings'
own map ``z -> q`` (``Couplings.fill``), on chains of couplings with a fixed coordinate among them."""

from __future__ import annotations

import numpy as np

from mcdm_pin.model.couplings import Coupling, Couplings


def _couplings():
    """Eight hinge coordinates: 1 <- 0, 2 <- 1 (a chain), 3 fixed, 4 <- 3 (coupled to a fixed one),
    6 <- 2 (a chain of three); 0, 5 and 7 independent."""
    items = [Coupling(6, 2, (0.3, -1.2, 0.0, 0.7, 0.0), "e"), Coupling(1, 0, (0.1, -0.5, 0.3, 0.2, -0.1), "a"),
             Coupling(2, 1, (0.0, 2.0, -0.3, 0.1, 0.05), "b"), Coupling(3, -1, (0.4, 0, 0, 0, 0), "c"),
             Coupling(4, 3, (0.0, 1.0, 0.5, 0, 0), "d")]
    return Couplings(np.arange(8), items, [f"x{i}" for i in range(8)])


def test_basis_equals_finite_differences_of_the_coupled_map():
    cs = _couplings()
    assert cs.independent.tolist() == [0, 5, 7]
    rng = np.random.default_rng(5)

    def q_of(z):
        q = np.zeros(8)
        q[cs.independent] = z
        return cs.fill(q)[0]

    for _ in range(20):
        z = rng.uniform(-1.0, 1.0, cs.n)
        N = cs.basis(q_of(z))
        h = 1e-6
        fd = np.column_stack([(q_of(z + h * e) - q_of(z - h * e)) / (2 * h) for e in np.eye(cs.n)])
        assert np.abs(N - fd).max() < 1e-8 * max(1.0, np.abs(fd).max())
        assert not N[3].any() and not N[4].any()  # a fixed coordinate and the one coupled to it
        assert np.count_nonzero(N[6]) == 1 and N[6, 0] != 0.0


class _Cubic:
    """A coupling given by a function (as OpenSim's are): ``(f, f', f'')``."""

    def value(self, x):
        return 0.2 * x ** 3 - x, 0.6 * x ** 2 - 1.0, 1.2 * x


def test_check_accepts_what_fill_makes_and_names_the_first_coordinate_that_breaks_a_coupling():
    """``check`` (one compiled pass, each coupling at the given values of its source) accepts every
    state ``fill`` makes, chains, fixed coordinates and a function included, and refuses a dependent
    moved by 1e-6 in ``q``, ``v`` or ``a`` (or made NaN), naming it and the coupling."""
    import pytest

    from mcdm_pin.exceptions import StateError

    items = list(_couplings().items) + [Coupling(5, 0, (0.0,) * 5, "f", function=_Cubic())]
    cs = Couplings(np.arange(8), items, [f"x{i}" for i in range(8)])
    rng = np.random.default_rng(7)
    for _ in range(20):
        q, v, a = cs.fill(*rng.uniform(-1.0, 1.0, (3, 8)))
        cs.check(q, v, a)
        cs.check(q)
        cs.check(q, v)
        for what, x in (("q", q), ("v", v), ("a", a)):
            for dep, coupling in ((6, "e"), (2, "b"), (4, "d"), (5, "f")):
                for bad in (1e-6, np.nan):
                    y = x.copy()
                    y[dep] = y[dep] + bad
                    args = dict(q=q, v=v, a=a) | {what: y}
                    with pytest.raises(StateError, match=rf"^{what}: coordinate 'x{dep}' is .* but coupling "
                                                          rf"'{coupling}' makes it"):
                        cs.check(**args)


def test_project_equals_the_dense_products_with_the_basis():
    """``project`` (one compiled pass: ``N`` has one entry at most per row) gives ``basis``'s ``N``, and
    ``L N``, ``N^T tau`` equal to the dense products to rounding."""
    items = list(_couplings().items) + [Coupling(5, 0, (0.0,) * 5, "f", function=_Cubic())]
    cs = Couplings(np.arange(8), items, [f"x{i}" for i in range(8)])
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = cs.fill(rng.uniform(-1.0, 1.0, 8))[0]
        L, tau = rng.normal(size=(11, 8)), rng.normal(size=8)
        N, LN, Nt = cs.project(q, L, tau)
        assert np.array_equal(N, cs.basis(q))
        np.testing.assert_allclose(LN, L @ N, rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(Nt, N.T @ tau, rtol=1e-14, atol=1e-14)
