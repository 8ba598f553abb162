"""The named structures the compiled solvers take and return.

numba compiles a ``collections.namedtuple`` into a struct whose fields a kernel reads by name
(``qp.H``, ``limits.max_pivots``) and builds one as it returns (``Answer(...)``); on the
uncompiled path the same classes are plain Python tuples. A kernel then takes a few structures
instead of two dozen positional arrays and numbers, and returns one structure instead of a 12-tuple.

Every field's type is fixed by what the library passes (C-ordered float64 arrays, ``int`` limits,
``float`` tolerances): one compiled specialisation serves every call.

**At the boundary, plain tuples.** An entry point that Python calls at every instant takes its
structures as plain tuples (``tuple(qp)``) and names them again in its first line
(``qp = QP(*qp)``); the kernels it calls get the structures as before. numba's dispatcher types a
plain tuple of arrays and numbers in C, but a namedtuple through its Python ``typeof``: 0.7-3.0 us
more per call, 3.0 with a ``QP``, ``Cones`` and ``Limits`` (docs/speed.md, "Plain tuples at the
kernels' boundary"). :func:`mcdm_pin.solvers._fast.answer_unique`, which Python calls rarely and
the kernels often, keeps the named ones. The builders from a
:class:`~mcdm_pin.problem.QPData` and a :class:`~mcdm_pin.settings.Settings` are
:func:`mcdm_pin.solvers.active_set.kernel_qp`, ``kernel_cones`` and ``kernel_limits``.

:data:`KERNEL_STRUCTURES` marks this module as a kernel source for :mod:`mcdm_pin.jit`: numba's
cache keys a kernel by its own file only, so an edit here must invalidate the compiled kernels too.
"""

from __future__ import annotations

from collections import namedtuple

QP = namedtuple("QP", ["H", "d0", "F", "c", "r", "A", "b", "lb", "ub", "strict"])
QP.__doc__ = """A convex QP: minimise ``1/2 x^T H x + c^T x + r`` subject to ``A x = b`` and
``lb <= x <= ub`` (bounds may be infinite). ``H`` (n, n) is what the active-set solver reads;
``d0`` (n,) and ``F`` (r, n) are the same ``H = diag(d0) + F^T F`` for the interior-point
method's Newton systems (empty, (0,) and (0, n), where only the active-set solver runs);
``strict``: ``H`` is positive definite (``d0 > 0``), so the optimum is unique."""

Cones = namedtuple("Cones", ["G", "gc", "ax", "tn", "basis0", "cosr", "basis"])
Cones.__doc__ = """The K interaction cones, stacked: the force ``F_k = gc[k] + G[k] x`` (G (K, 3, n),
gc (K, 3)) within the half-angle whose tangent is ``tn[k]`` (K,) and cosine ``cosr[k]`` of the
unit axis ``ax[k]`` (K, 3); ``basis0`` (K, 3) a unit vector normal to each axis (the first
surface direction tried) and ``basis`` (K, 2, 3) the plane normal to each axis."""

Limits = namedtuple("Limits", ["max_pivots", "max_newton", "step_tol", "primal_tol", "dual_tol", "eom_tol",
                               "reg_rel", "stationary_tol", "surface_tol", "settle_tol", "cone_tol", "keep_rel", "near",
                               "unique_rel", "penalty", "max_iter", "eps", "crossover_gap", "ncorr", "rank_tol",
                               "box_weight", "crossover_attempts", "pivot_drop", "refine_gap", "step_fraction",
                               "min_step", "certificate_rel"])
Limits.__doc__ = """The compiled solvers' limits and tolerances, each a field of
:class:`~mcdm_pin.settings.Settings` (``kernel_limits`` copies them): the active-set solver's pivot
limit (``max_pivots``: the warm start's, the polish's or a crossover's), cone Newton steps and
tolerances (``active_set_max_newton``, ``active_set_step``, ``_primal``, ``_dual``, ``_eom``,
``_reg``, ``_stationary``, ``_surface``, ``_settle``, ``_cone``, ``_keep``); the uniqueness test's (``near``:
``active_set_from_solution``, ``unique_rel``, ``penalty``: ``unique_penalty``); the interior-point
method's (``ipm_max_iter``, ``_eps``, ``_crossover_gap``, ``_correctors``, ``_rank_tol``,
``_start_box_weight``, ``_crossover_attempts``, ``_pivot_drop``, ``_refine_gap``, ``_step_fraction``,
``_min_step``, ``_certificate``)."""

Answer = namedtuple("Answer", ["code", "x", "y", "z", "z_cone", "objective", "iterations", "held", "mus", "dirs",
                               "next_state", "unique"])
Answer.__doc__ = """A compiled solver's answer: ``code`` (the kernel's status), the point ``x``,
the equations' multipliers ``y``, the bounds' ``z`` (base convention) and the cones' ``z_cone``
(K, 3), the ``objective``, ``iterations`` (KKT systems solved, or the interior-point iterations),
the cones ``held`` with a positive multiplier, their multipliers ``mus`` and surface directions
``dirs``, the bounds' guess for the next instant ``next_state`` and ``unique`` (1 proven unique,
0 not proven). Which fields mean something for which code: the kernel's docstring."""

ActiveSetRun = namedtuple("ActiveSetRun", ["code", "f", "mus", "grad", "state", "cact", "dirs", "next_state", "y",
                                           "sets", "solves"])
ActiveSetRun.__doc__ = """What :func:`mcdm_pin.solvers._kkt.active_set_run` returns (its docstring)."""

IPMRun = namedtuple("IPMRun", ["code", "x", "y", "z", "z_cone", "iterations", "state", "cact", "mus", "dirs"])
IPMRun.__doc__ = """What :func:`mcdm_pin.solvers._ipm.ipm_solve` returns (its docstring)."""

NewtonSystem = namedtuple("NewtonSystem", ["B", "rf", "Ct", "cg", "fold", "LK", "F", "T", "A", "gram"])
NewtonSystem.__doc__ = """The interior-point method's reduced Newton system (:mod:`._ipm_newton`): its
structure (:func:`._ipm_structure.structure`: ``B``, ``rf``, ``Ct``, ``cg``, ``fold``), its Cholesky
factor ``LK`` (made in place each iteration), the objective's factor ``F``, cone rows ``T`` and
equations ``A`` that refinement multiplies by, and how the factor reads ``B``
(:func:`._ipm_newton.gram_plan`)."""

Scaling = namedtuple("Scaling", ["dinv", "dbar", "ru", "rl", "W2", "Wm", "Winv", "lamc"])
Scaling.__doc__ = """The interior-point method's scaling at an iterate (arrays updated in place each
iteration): the barrier's diagonal ``dbar`` (``D = d0 + z/s`` on the bounds) and its floored
inverse ``dinv``, the bounds' ``z/s`` (``ru`` upper, ``rl`` lower), and each cone's Nesterov-Todd
``W^2``, ``W``, ``W^-1`` and ``lambda = W z`` (K, 3, 3) x 3 and (K, 3)."""

Slacks = namedtuple("Slacks", ["su", "zu", "sl", "zl", "sc", "zc"])
Slacks.__doc__ = """The interior-point method's slacks and their duals (updated in place): the upper
bounds' ``su, zu``, the lower bounds' ``sl, zl`` and the cones' ``sc, zc`` (K, 3)."""

KKTMeasures = namedtuple("KKTMeasures", ["eom", "bound", "cone_deg", "stationarity", "complementarity"])
KKTMeasures.__doc__ = """The answer check's residuals at a point (:func:`mcdm_pin.solvers.check.kkt_residuals`, its
module docstring): relative equation-of-motion residual, bound violation, cone violation in degrees,
relative stationarity and complementarity (NaN without duals)."""

Tensions = namedtuple("Tensions", ["index", "passive", "gain", "a_min", "bound_abs"])
Tensions.__doc__ = """The muscles' state at an instant as the answer check reads it to give their activations
(:func:`mcdm_pin.model.muscles.activation`): the muscles' cables ``index`` (k,), their tensions'
``passive`` part and ``gain`` per unit of activation, their ``a_min`` (k,), and the check's
``bound_abs`` (N); ``index`` empty: no muscles."""

Face = namedtuple("Face", ["free", "held", "S", "rest", "Vt", "lb", "ub", "E", "x", "direct", "steps"])
Face.__doc__ = """The optimal face through an answer, as :func:`mcdm_pin.solvers._unique.face_setup` gives it
(:func:`mcdm_pin.solvers.least_norm.stage2_problem`): the variables not strongly active at a bound
``free`` (n,), the cones strongly held ``held`` (K,), the coordinates ``S`` whose unit rows are among
the face's rows and the others ``rest``, an orthonormal basis ``Vt`` (rows over ``rest``) of the
other rows' parts there; and the least-norm problem's bounds ``lb``, ``ub`` (n,: a free variable's
own, infinite at a strongly active bound, ``x_i`` at both for ``i`` in ``S``) and equations' rows
``E`` (``Vt`` placed in the columns ``rest``); the least-norm point of the face ``x`` (n,) and
whether it answers the least-norm problem, ``direct`` (the problem in the face's free directions,
with its bounds, and every cone not held met there: :func:`mcdm_pin.solvers._face_qp.face_least_norm`),
in ``steps`` KKT systems of the face's size."""

KERNEL_STRUCTURES = (QP, Cones, Limits, Answer, ActiveSetRun, IPMRun, NewtonSystem, Scaling, Slacks, KKTMeasures, Face,
                     Tensions)
"""The structures above (the marker :func:`mcdm_pin.jit.kernel_sources` looks for)."""
