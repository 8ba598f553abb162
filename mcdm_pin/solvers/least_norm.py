r"""One answer: among equally optimal points, the one of least ``|x|^2`` (refining stage ``least_norm``).

The interaction objective is only positive semidefinite: where a joint has ``alpha = 0``, or the
cables outnumber what the weighted wrench rows see, a whole face of optimal forces exists, and which
point a back-end returns depends on its path (on the human arm's ``abduct``, case 3, the elbow's force
peaked at 1297 N with one back-end and 76 N with another). This stage makes the answer unique:

**Stage 2 (lexicographic).** For a convex quadratic objective every optimal point has the same
``P x`` and ``c^T x`` (if ``x_1, x_2`` are optimal, convexity along the segment forces
``(x_1 - x_2)^T P (x_1 - x_2) = 0``, hence ``P x_1 = P x_2``, and then equal objectives give equal
``c^T x``). So the optimal set is the feasible set cut by ``P x = P x*, c^T x = c^T x*``, and

.. math:: \min_x\ \tfrac12 \sum_i w_i x_i^2 \quad \text{s.t. the original constraints},\
          E (x - x^*) = 0,

with ``E`` an orthonormal basis of the part of ``span(rows of P, c^T)`` not already in the equations'
row space (rank-revealed by an SVD; for ``P = diag(d) + F^T F`` the rows of ``F`` and the ``e_i`` with
``d_i != 0``), picks the least-norm optimum: a strictly convex problem with one answer, solved by
the same back-end's chain (``w``: ``QPData.norm_weight``, ones unless the problem was scaled).

**On the face itself first.** The face's rows leave free directions ``N`` (orthonormal, over the
coordinates not pinned: the right singular vectors the SVD above leaves out), and the least-norm
problem is one in their ``k`` coordinates: ``x = x* + N^T t``, the bounds of the coordinates not
pinned, and the cones the face does not hold. Its bounds are solved by a ``k``-sized active set
(:mod:`._face_qp`); where the point also meets every cone not held, it is the answer (the least-norm
point of a larger set that lies in the problem's own), and the chain runs only where a cone not held
breaks there or the small method does not converge. Over the shipped robots' least-norm instants the
face answers every one (the human arm's ``abduct``, case 3, has its cone not held at 69 of 151, met
along the face), and its point equals the chain's answer to 7.9e-15 of the largest force.

**A constant objective.** Where ``P = 0`` and ``c = 0`` (every joint's weights zero: case 2 on a robot
without ball joints, as the CASPR import weighs them) every feasible point is optimal, and the least-norm
optimum is the least-norm feasible point. :class:`FlatObjective`, the first stage of every chain,
solves that problem at once: the first-stage answer would be any point of a flat objective, which
the active-set solver reaches only by degenerate pivoting (SJTUSnake's case 2: the warm start
cycled at every instant, 18 ms each), and the least-norm stage would then solve the same problem.

**Skipped when unique.** The first-stage optimum is unique when the Hessian (plus the active cones'
curvature) is positive definite on the null space of the strongly active constraints (the equations,
the bounds and cones whose multiplier exceeds ``unique_rel`` of the gradient's scale): the
second-order sufficient condition, which for a convex problem means a unique minimiser.
:func:`is_unique` proves it in one of two ways, each a Cholesky factor; the answer records the
outcome (``Solution.unique``, the results' ``unique`` column: true where proven):

- **a vertex:** the active rows ``J`` on the free variables have full column rank (``J^T J`` has a
  factor), so the null space is empty;
- **the Hessian made definite along the rows:** ``H + gamma J^T J - thr I`` has a factor (``thr =
  unique_rel`` times the Hessian's largest entry, ``gamma = unique_penalty`` times that entry over
  ``J^T J``'s). Then ``z^T H z = z^T (H + gamma J^T J) z > thr |z|^2`` for every ``z`` with ``J z =
  0``: the second-order condition, without forming the null space (an SVD of ``J``) or the reduced
  Hessian's eigenvalues.

A factor that fails proves nothing (``gamma`` is finite), and the least-norm stage then runs: where
the optimum is unique after all, its face is that one point and the stage returns it. No exact test
(the null space by an SVD, the reduced Hessian's smallest eigenvalue) follows the two factors: over
the shipped robots it never proved what they could not, and it cost an SVD and an eigenvalue solve on
every answer with a face of optima (``tools/uniqueness_survey.py``; docs/speed.md, "The uniqueness
test without its exact step").
(``tests/test_warm_fast.py::test_uniqueness_shortcut_only_claims_what_the_null_space_test_proves``
checks the second factor against the exact test.)
"""

from __future__ import annotations

import numpy as np

from .. import jit
from ..settings import DEFAULT, Settings
from ..vocabulary import FLAT_OBJECTIVE_STAGE
from .active_set import ActiveSet, kernel_cones, kernel_limits, kernel_qp
from .base import OPTIMAL, Solution, Stage
from .check import project_to_bounds


def _strongly_active(qp, sol: Solution, settings: Settings, curvature: bool = True):
    """(free mask, rows of the active cones' gradients, their curvature) at ``sol`` (``curvature``
    false: the curvature is not formed, ``None``; thresholds: ``settings``' ``unique_rel`` and
    ``active_set_from_solution``)."""
    x, z = sol.x, sol.z
    grad = qp.gradient(x)
    gscale = max(np.abs(grad).max(initial=0.0), np.abs(qp.c).max(initial=0.0), 1e-300)
    thr = settings.unique_rel * gscale
    near = settings.active_set_from_solution
    at_l = (x - qp.lb <= near * (1.0 + np.abs(qp.lb))) & (z < -thr)
    at_u = (qp.ub - x <= near * (1.0 + np.abs(qp.ub))) & (z > thr)
    free = ~(at_l | at_u)
    rows, curv = [], (np.zeros((qp.n, qp.n)) if curvature else None)
    for k, cone in enumerate(qp.cones):
        lam = sol.z_cone[k]
        mu = lam[0] * np.cos(np.radians(cone.angle_deg))
        if not mu > thr:
            continue
        F = cone.force(x)
        perp_vec = F - float(cone.axis @ F) * cone.axis
        perp = float(np.linalg.norm(perp_vec))
        if perp <= 1e-12 * max(float(np.linalg.norm(F)), 1e-300):  # held at the apex: F = 0
            rows += [(k, r) for r in cone.G]
            continue
        nhat = perp_vec / perp
        # on the surface with this direction for every optimum: the surface row and the
        # perpendicular direction normal to it
        rows.append((k, (nhat - cone.tan * cone.axis) @ cone.G))
        e, h = cone.axis, nhat  # e x h, by hand: np.cross costs ~8x as much on 3-vectors
        rows.append((k, np.array([e[1] * h[2] - e[2] * h[1], e[2] * h[0] - e[0] * h[2],
                                  e[0] * h[1] - e[1] * h[0]]) @ cone.G))
        if curvature:
            Pp = np.eye(3) - np.outer(cone.axis, cone.axis) - np.outer(nhat, nhat)
            curv += mu * cone.G.T @ Pp @ cone.G / perp
    return free, rows, curv


def is_unique(qp, sol: Solution, settings: Settings = DEFAULT) -> bool:
    """Whether the optimum ``sol`` is provably unique (module docstring). Needs its duals; ``False``
    without them (not proven)."""
    if qp.strictly_convex():  # P = diag(d) + F^T F with d > 0 is positive definite (case 1)
        return True
    if sol.z is None or (qp.cones and sol.z_cone is None):
        return False
    decided = _compiled_unique(qp, sol, settings)
    if decided is not None:
        return decided
    free, rows, _ = _strongly_active(qp, sol, settings, curvature=False)  # the curvature only if needed below
    nf = int(free.sum())
    if nf == 0:
        return True
    J = _active_rows(qp, free, rows)
    if _full_column_rank(J):  # the usual case (a vertex): the null space is empty
        return True
    curv = _strongly_active(qp, sol, settings)[2]
    H = (qp.P + curv)[np.ix_(free, free)]
    hscale = max(np.abs(qp.P).max(initial=0.0), 1e-300)
    return _definite_beyond(H, J, settings.unique_rel * hscale, hscale, settings.unique_penalty)


def _active_rows(qp, free, rows) -> np.ndarray:
    """``J``: the equations' and the held cones' rows (``rows`` of :func:`_strongly_active`) on the
    ``free`` variables."""
    nf = int(free.sum())
    if not (len(qp.b) or rows):
        return np.zeros((0, nf))
    return np.vstack([qp.A[:, free]] + [np.asarray(r)[free][None, :] for _, r in rows])


def _full_column_rank(J) -> bool:
    """Whether ``J`` has full column rank: ``J^T J`` has a Cholesky factor whose smallest pivot squared
    is above 1e-10 of its largest entry (the compiled test's threshold)."""
    if J.shape[0] < J.shape[1]:
        return False
    JtJ = J.T @ J
    try:
        Lc = np.linalg.cholesky(JtJ)
    except np.linalg.LinAlgError:
        return False
    return bool(np.diag(Lc).min() ** 2 > 1e-10 * max(np.abs(JtJ).max(), 1e-300))


def _definite_beyond(H, J, thr: float, hscale: float, penalty: float) -> bool:
    """The second factor of the module docstring: whether ``H + gamma J^T J - thr I`` is positive definite
    (has a Cholesky factor; ``gamma`` from ``penalty``, :attr:`~mcdm_pin.settings.Settings.unique_penalty`)."""
    JtJ = J.T @ J
    big = float(np.abs(JtJ).max(initial=0.0))
    gam = penalty * hscale / big if big > 0.0 else 0.0
    try:
        np.linalg.cholesky(H + gam * JtJ - thr * np.eye(len(H)))
    except np.linalg.LinAlgError:
        return False
    return True


def _compiled_unique(qp, sol: Solution, settings: Settings) -> bool | None:
    """The rest of :func:`is_unique` compiled (:func:`._fast.answer_unique` past its first test, the
    same steps and thresholds); ``None`` while the kernels are not compiled."""
    if not jit.ready():
        return None
    c_ = np.ascontiguousarray
    zc = sol.z_cone if qp.cones else _NO_3
    # (``strict`` False: is_unique's first test has been made)
    return bool(jit.kernels("solvers._fast").answer_unique(
        c_(sol.x, dtype=float), c_(sol.z, dtype=float), c_(zc, dtype=float).reshape(len(qp.cones), 3),
        kernel_qp(qp)._replace(strict=False), kernel_cones(qp), kernel_limits(settings, settings.polish_max_pivots)))


_NO_3 = np.zeros((0, 3))


def optimal_face_rows(qp, sol: Solution | None = None, settings: Settings = DEFAULT) -> np.ndarray:
    """An orthonormal basis of the rows that are constant on the optimal face: the equations, the rows
    of ``P``, ``c^T``, and, from the duals of ``sol`` (the same for every optimal point), the bounds
    and cone surfaces whose multiplier is not zero (complementarity holds them for every optimum).

    Many of these rows are unit rows ``e_i`` (a diagonal entry of ``P``, a strongly active bound):
    they span the coordinates ``S``, and every other row's part on ``S`` lies in their span, so the
    basis is the ``e_i`` (``i`` in ``S``) and an orthonormal basis of the other rows' parts on the
    remaining coordinates, rank-revealed by an SVD (module docstring) of that smaller matrix (each
    row normalised first, the threshold relative to the largest singular value of the whole, at
    least 1). On MyoSuite's arm (85 variables, ~60 of them in ``S``) that SVD is 4x25 instead of 8x85
    in flops' terms: most of the stage's cost."""
    _, _, S, rest, Vt = _face(qp, sol, settings)[:5]
    E = np.zeros((len(S) + len(Vt), qp.n))
    E[np.arange(len(S)), S] = 1.0
    E[len(S):, rest] = Vt
    return E


def _face(qp, sol: Solution | None, settings: Settings):
    """The optimal face through ``sol.x`` (its duals' strongly active set; ``sol`` ``None`` or without
    duals: none) as a :class:`._structs.Face`: the variables not strongly active at a bound, the
    cones strongly held, the coordinates ``S`` whose unit rows are among the face's rows, the others
    ``rest``, an orthonormal basis ``Vt`` (rows over ``rest``) of the other rows' parts there
    (:func:`optimal_face_rows`), and :func:`stage2_problem`'s bounds and rows. One compiled pass
    (:func:`._unique.face_setup`, with the strongly active set of the compiled uniqueness test)."""
    n, K = qp.n, len(qp.cones)
    c_ = np.ascontiguousarray
    # the objective's rows whose curvature is above 1e-12 of the largest: one below it changes the
    # objective by less than its rounding along any move of the forces' size (a moment weighted
    # 3e-277 beside forces weighted 1, normalised into a row of its own, pinned each back-end's
    # optimum to its own moment: three "least-norm" answers, |f| 623, 637 and 73 N)
    if qp.P_factor is not None and qp.P_diag is not None:
        F, d = qp.P_factor, qp.P_diag
    else:  # the eigenvectors of the nonzero eigenvalues, of norm one: the curvature test keeps them all
        w, V = np.linalg.eigh(qp.P)
        F, d = V[:, w > 1e-12 * max(np.abs(w).max(initial=0.0), 1e-300)].T, np.zeros(n)
    duals = sol is not None and sol.z is not None
    x = c_(sol.x, dtype=float) if sol is not None else np.zeros(n)
    z = c_(sol.z, dtype=float) if duals else np.zeros(n)  # (no duals: nothing strongly active)
    zc = c_(sol.z_cone, dtype=float).reshape(K, 3) if duals and K and sol.z_cone is not None else np.zeros((K, 3))
    return jit.kernels("solvers._unique").face_setup(  # (plain tuples at the boundary: solvers._structs)
        x, z, zc, tuple(kernel_qp(qp)), tuple(kernel_cones(qp)),
        tuple(kernel_limits(settings, settings.polish_max_pivots)),
        c_(F, dtype=float).reshape(-1, n), c_(d, dtype=float), _norm_weight(qp))


def stage2_problem(qp, sol: Solution, settings: Settings = DEFAULT, face=None):
    """The least-norm problem over the optimal face of ``qp`` through ``sol.x`` (module docstring):
    every row constant on the face is an equation; the strongly active bounds and cones are among
    them (their inequalities are dropped: on the face they hold with equality, and an inequality
    without interior would stall an interior-point method). A unit row ``e_i`` pins ``x_i`` to
    ``x*_i``: it becomes the bounds ``lb_i = ub_i = x*_i`` (a fixed variable, which every stage
    takes out of its linear systems), not an equation: on MyoSuite's arm 55 of the face's 84 rows
    are unit rows, and 55 of its 85 variables leave the active set's KKT system. ``face``: the
    :class:`._structs.Face` of :func:`_face` when made already."""
    face = _face(qp, sol, settings) if face is None else face
    held = face.held
    if not held.any():
        return least_norm_problem(qp, A=face.E, b=face.E @ sol.x, lb=face.lb, ub=face.ub)
    keep = ~held
    if not keep.any():  # (every cone held: the problem has none, whose arrays are made once per size)
        return least_norm_problem(qp, A=face.E, b=face.E @ sol.x, lb=face.lb, ub=face.ub, cones=[])
    # the cones not held, their stacked arrays and constants taken from the problem's (not stacked again)
    names, angles, cosr, basis = qp.cone_consts()
    return least_norm_problem(qp, A=face.E, b=face.E @ sol.x, lb=face.lb, ub=face.ub,
                              cones=[c for k, c in enumerate(qp.cones) if keep[k]],
                              cone_arrays=tuple(a[keep] for a in qp.cone_arrays()),
                              cone_consts=(tuple(nm for k, nm in enumerate(names) if keep[k]), angles[keep],
                                           cosr[keep], basis[keep]))


def least_norm_problem(qp, **changes):
    """``qp`` with the least-norm objective ``1/2 sum_i w_i x_i^2`` and ``changes`` to its other fields
    (:meth:`QPData.replace`); ``w`` is ``QPData.norm_weight`` divided by its largest entry (the same
    minimiser). A scaled copy of a constant objective carries weights of the order of its unit's
    inverse (2^22 on CoGiRo's platform), on which the interior-point method ran into its iteration
    limit at a third of the instants."""
    n = qp.n
    return qp.replace(P=None, P_diag=_norm_weight(qp), P_factor=np.zeros((0, n)), c=np.zeros(n), r=0.0, **changes)


def _norm_weight(qp) -> np.ndarray:
    """The least-norm objective's weights ``w`` (:func:`least_norm_problem`)."""
    return np.ones(qp.n) if qp.norm_weight is None else qp.norm_weight / qp.norm_weight.max()


class FlatObjective(Stage):
    """Answering stage, first of every chain: where the objective is a constant
    (:meth:`QPData.constant_objective`), the least-norm feasible point (module docstring), solved by
    ``inner`` (the least-norm stage's chain). It answers with multipliers zero, which with a constant
    objective certify any feasible point, and as the least-norm optimum (``unique=False``), which
    the refining stages keep."""

    name = FLAT_OBJECTIVE_STAGE

    def __init__(self, inner, settings: Settings = DEFAULT):
        self.inner = inner
        self.settings = settings

    def run(self, qp, sol, deadline):
        if not qp.constant_objective():
            return None
        out = self.inner.solve(least_norm_problem(qp), deadline=deadline)
        if out.status != OPTIMAL:
            return out.but(stage=f"{self.name}>{out.stage}") if out.final else None
        x = out.x
        return out.but(objective=qp.objective(x), y=np.zeros(len(qp.b)), z=np.zeros(qp.n),
                       z_cone=np.zeros((len(qp.cones), 3)), unique=False, stage=f"{self.name}>{out.stage}")


class LeastNorm(Stage):
    """Refining stage: the least-norm optimum (module docstring).

    Args:
        inner: the chain that solves stage 2 (a :class:`~.cascade.Cascade` of the same back-end, without
            this stage), seeded with the first stage's answer.
        settings: the uniqueness test's thresholds and the projection's (``unique_*``,
            ``active_set_from_solution``, ``bound_snap_rel``).
    """

    name = "least_norm"
    refines = True

    def __init__(self, inner, settings: Settings = DEFAULT):
        self.inner = inner
        self.settings = settings

    def reset(self):
        self.inner.reset()

    def run(self, qp, sol, deadline):
        if sol.unique is not None:
            return sol
        s = self.settings
        if not sol.unique_tested and is_unique(qp, sol, s):  # (a compiled answer was tested: not proven)
            return sol.but(unique=True)
        face = _face(qp, sol, s)
        if face.direct:  # the face's least-norm point, its bounds kept and its cones met: the answer
            return self._answer(qp, sol, face.x, int(face.steps))
        stage2 = stage2_problem(qp, sol, s, face)
        if sol.active is None:
            sol = sol.but(active=ActiveSet.from_duals(qp, sol, s.active_set_from_solution))
        out = self.inner.solve(stage2, hint=sol, deadline=deadline)
        if out.status != OPTIMAL:
            note = (f"least-norm stage failed ({out.status}: {out.message}); the answer is optimal but "
                    f"may not be the least-norm one")
            return sol.but(unique=False, message=f"{sol.message}; {note}" if sol.message else note)
        return self._answer(qp, sol, project_to_bounds(qp, out, s).x, out.iterations)

    def _answer(self, qp, sol, x, iterations):
        """``sol`` moved to the least-norm optimum ``x``, found in ``iterations`` linear solves. Stage 2's
        multipliers of the original rows are not those of the original problem: the first stage's
        duals stay (they certify ``x`` too: it lies on the same optimal face), and so does its active
        set, the next instant's guess for its first stage (a guess made again from the duals at ``x``
        costs a pass over the bounds and cones and saves no KKT solve: docs/speed.md)."""
        return sol.but(x=x, objective=qp.objective(x), unique=False, stage=f"{sol.stage}>{self.name}",
                       iterations=sol.iterations + iterations, verified=False)
