r"""Answering stage: the compiled interior-point method with crossover (:mod:`._ipm`), the answer of
every instant without a warm neighbour.

It needs no starting point: Mehrotra's predictor-corrector method reaches a relative duality gap of
``IPM_CROSSOVER_GAP`` in 9-11 iterations on the neck, from where the active set read off the
iterate is handed to the compiled active-set solver, whose answer is verified against the full KKT
conditions (an exact optimum, to rounding). A certificate of primal infeasibility ends the solve
with ``infeasible``; an iteration limit or a numerical breakdown leaves the instant to the next stage.
"""

from __future__ import annotations

import numpy as np

from .. import jit
from ..qp import ConeData, QPData, perpendicular_basis
from . import _fast, _ipm
from ..settings import DEFAULT, Settings
from .active_set import compiled_answer, kernel_cones, kernel_limits, kernel_qp
from .base import INACCURATE, INFEASIBLE, OPTIMAL, Solution, Stage, failure

REASONS = {_ipm.MAX_ITER: "iteration limit", _ipm.NUMERICAL: "numerical breakdown (the step vanished)"}


def p_structure(qp) -> tuple[np.ndarray, np.ndarray]:
    """``(d0, F)`` with ``P = diag(d0) + F^T F``: the problem's own (:attr:`QPData.P_diag`,
    ``P_factor``) when it has them, else the diagonal of a diagonal ``P``, else a factor from the
    eigenvalues of ``P`` (those above 1e-14 of the largest)."""
    if qp.structured:
        return np.asarray(qp.P_diag, dtype=float), np.asarray(qp.P_factor, dtype=float).reshape(-1, qp.n)
    P = np.asarray(qp.P, dtype=float)
    d = np.diag(P).copy()
    if not np.any(P - np.diag(d)):
        return d, np.zeros((0, qp.n))
    w, V = np.linalg.eigh(0.5 * (P + P.T))
    keep = w > 1e-14 * max(w.max(initial=0.0), 1e-300)
    return np.zeros(qp.n), (np.sqrt(w[keep])[:, None] * V[:, keep].T)


def ipm_arguments(qp, settings: Settings = DEFAULT) -> tuple:
    """The arguments of :func:`._fast.ipm_answer` for ``qp``: its :class:`._structs.QP` with ``P``'s
    structure (:func:`p_structure`), its :class:`._structs.Cones` and the limits and tolerances of
    ``settings`` (``ipm_*``, ``active_set_*``, ``unique_*``; each crossover's pivot limit
    ``ipm_crossover_pivots``). The kernel takes each as a plain tuple (:mod:`._structs`)."""
    return (kernel_qp(qp, p_structure(qp)), kernel_cones(qp), kernel_limits(settings, settings.ipm_crossover_pivots))


def ipm_solve(qp, settings: Settings = DEFAULT) -> Solution:
    """Solve ``qp`` with the compiled interior-point method (``settings``: :func:`ipm_arguments`): one
    compiled call (:func:`._fast.ipm_answer`) makes the cone rows, solves, and after a crossover
    computes the answer's duals, the next guess (:func:`.active_set.active_solution` in numpy) and
    whether the optimum is provably unique (:func:`.least_norm.is_unique`).

    An equation without a variable whose right-hand side is not zero (``0 = b_i``: a coordinate that
    no cable or actuator moves, under a load) is its own certificate of infeasibility, given before
    the iterations: the method's iterates do not settle on a certificate along such a row (on a
    four-variable problem with one of them it ran to its iteration limit:
    ``tests/test_ipm_fixed.py``)."""
    empty = _empty_rows(qp)
    if len(empty):
        rows = f"rows {', '.join(map(str, empty.tolist()))} have" if len(empty) > 1 else f"row {empty[0]} has"
        return failure(qp.n, INFEASIBLE, f"no point meets the equation of motion: its {rows} no variable and a "
                                         f"nonzero right-hand side", 0, stage="ipm")
    out = jit.kernels("solvers._fast").ipm_answer(*map(tuple, ipm_arguments(qp, settings)))  # (plain: ._structs)
    n, it = qp.n, int(out.iterations)
    if out.code == _ipm.CROSSOVER:
        return compiled_answer(qp, out, stage="ipm")
    if out.code == _ipm.SOLVED:
        return Solution(out.x, OPTIMAL, qp.objective(out.x), y=out.y, z=out.z, z_cone=out.z_cone, iterations=it,
                        stage="ipm", verified=False)
    if out.code == _ipm.INFEASIBLE_CERT:
        what = "the bounds and the cones" if qp.cones else "the bounds"
        return failure(n, INFEASIBLE, f"no point meets the equation of motion and {what} (an "
                                      f"infeasibility certificate of the interior-point method)", it, stage="ipm")
    return failure(n, INACCURATE, f"interior-point method: {REASONS.get(out.code, out.code)}", it, stage="ipm")


def _empty_rows(qp) -> np.ndarray:
    """The equations whose row of ``A`` is exactly zero and whose right-hand side is not."""
    A, b = qp.A, qp.b
    used = np.asarray(A).any(axis=1)
    if not len(b) or used.all():  # (the usual case: one pass)
        return np.zeros(0, dtype=int)
    return np.flatnonzero((b != 0.0) & ~used)


class IPMStage(Stage):
    """Answering stage: :func:`ipm_solve` (skipped only where a test switches the kernels off)."""

    name = "ipm"

    def __init__(self, settings: Settings = DEFAULT):
        self.settings = settings

    def run(self, qp, sol, deadline):
        if not jit.ready():
            return None
        out = ipm_solve(qp, self.settings)
        if not out.final and sol is not None:
            return None  # leave the earlier stage's note
        return out


def warm_calls():
    """The solvers' kernels with example arguments of the types the library passes (registered
    with :mod:`mcdm_pin.jit`): the Python code calls :func:`._fast.ipm_answer`, and the kernels it
    calls are compiled with it."""
    n = 2
    axis = np.array([0.0, 0.0, 1.0])
    cone = ConeData("j", np.ones((3, n)), np.zeros(3), axis, 30.0, perpendicular_basis(axis))
    qp = QPData(np.eye(n), np.zeros(n), 0.0, np.ones((1, n)), np.ones(1), np.zeros(n), np.ones(n), [cone])
    return [(_fast.ipm_answer, tuple(map(tuple, ipm_arguments(qp))))]  # (plain tuples: ._structs)


jit.register("mcdm_pin.solvers", warm_calls)
