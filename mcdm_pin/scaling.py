r"""Problem scaling: every back-end solves a copy of the problem whose magnitudes are of order one, and
the answer (point and duals) is mapped back.

Two things go wrong on badly scaled robots. A robot with grams next to tonnes and millimetres next to
metres gives equation-of-motion rows whose sizes differ by many orders of magnitude and columns of
``L^T`` of very different sizes (ProxQP's first-order iterations then stall, ``tests/test_conditioning.py``).
And a robot whose numbers are all large or all small (links of 1e6 kg, forces to 1e12 N; links of
1e-6 kg) meets absolute tolerances that mean nothing at its scale (Clarabel reported false
"infeasible" at 1e6 kg). With

.. math:: f = D x, \qquad A f = b \;\to\; (R A D)\, x = R b, \qquad
          F_k = g_k + G_k f \;\to\; s_k F_k = s_k g_k + (s_k G_k D)\, x

(:math:`R`, :math:`D` positive diagonal: Ruiz equilibration when the equation of motion spreads over
more than ``SPREAD`` (three decades), then the variables' unit set by their bounds and each row by
its size; :math:`s_k > 0` per cone: cones are invariant under positive scaling of :math:`F_k`), the
objective divided by its own size (each variable at its unit, or at its largest bound where that is
smaller), and bounds :math:`l/d \le x \le u/d`, the scaled problem has the
same solution set mapped by :math:`D`. The variables' unit is the size the equations ask for
(``|b_i| / max_j |A_ij|``), at least the geometric middle of the bounds, ``sqrt(max f_min * min limit)``
over the positive lower bounds ``f_min`` and the limits (the nonzero upper bounds, and the negative
lower bounds: an actuator's ``-U <= tau <= U`` says how large it may get, not how large it is; the
lower bounds alone when there is no limit), so that scaling every mass and every bound by
``k`` gives the same scaled problem whatever ``k`` (``tests/test_reference.py``). Every factor is a power of two (no rounding). A problem whose
factors all lie within ``SPREAD`` of one is passed through untouched (the usual case: the neck, the
arms), so well-scaled problems pay nothing.

The answer is unscaled (``f = D x``; ``y = o R y_s``, ``z = o z_s / d``, cone duals ``o s_k z_s``,
with ``o`` the objective's scale), its objective re-evaluated on the original problem, and the runner
then checks it against the *original* constraints, so scaling can never hide a violated constraint.
The least-norm stage keeps minimising the original ``|f|^2`` (the scaled copy carries the weights
``d^2``).

Use: ``ScaledSolver(get_solver("default"))`` is a :class:`~mcdm_pin.solvers.Solver` like any other.
Along a trajectory it keeps the last optimal instant's factors while the copy they make of the next
problem is well scaled (``ScaledSolver._scale``): consecutive instants nearly always share their
factors, and the one-pass test costs a fraction of making them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import jit
from .constraints import ConeData
from .problem import QPData
from .solvers.base import INACCURATE, OPTIMAL, Solution, Solver

SPREAD = 1e3
"""Scale only when some factor would exceed this (either way)."""
_NO_P = np.zeros((0, 0))
_NO_F = np.zeros(0)
_NO_ZC = np.zeros((0, 3))


def equilibrate(A: np.ndarray, sweeps: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """Ruiz equilibration: positive ``r`` (rows) and ``d`` (columns) with ``r_i |A_ij| d_j`` of order
    1 in every row and column (powers of two, so scaling adds no rounding). One call of the
    compiled :func:`mcdm_pin.model.kernels.ruiz` (compiled or not: mcdm_pin/jit.py)."""
    return jit.kernels("model.kernels").ruiz(np.ascontiguousarray(A, dtype=float), int(sweeps))


def _pow2(x):
    return np.exp2(np.round(np.log2(x)))


def spread(A: np.ndarray) -> float:
    """How badly scaled the rows and columns of ``A`` are: the larger of the ratios between the
    largest and smallest non-zero row maxima and column maxima of ``|A|`` (1 when ``A`` is zero).
    (The right-hand side is left out: an equation whose torque happens to be near zero is not badly
    scaled.) Compiled when the kernels are (:func:`mcdm_pin.model.kernels.spread`)."""
    if jit.ready():
        compiled = jit.kernels("model.kernels").spread  # (compiled or not: mcdm_pin/jit.py)
        # C order: one compiled specialisation (qp.A is often the transposed view L.T)
        return compiled(np.ascontiguousarray(A, dtype=float), np.zeros(0))
    B = np.abs(A)
    out = 1.0
    for v in (B.max(axis=1, initial=0.0), B.max(axis=0, initial=0.0)):
        v = v[v > 0]
        if len(v):
            out = max(out, float(v.max() / v.min()))
    return out


@dataclass
class Scaling:
    """``f = d x``; rows of ``A`` times ``r``; objective divided by ``obj``; cone ``k``'s force times
    ``cone[k]``."""

    d: np.ndarray
    r: np.ndarray
    obj: float
    cone: np.ndarray

    def fits(self, qp: QPData) -> bool:
        """Whether these factors have the shapes of ``qp``'s variables, equations and cones."""
        return len(self.d) == qp.n and len(self.r) == len(qp.b) and len(self.cone) == len(qp.cones)

    def unscale(self, qp: QPData, sol: Solution) -> Solution:
        """``sol`` (an answer of the scaled copy of ``qp``) mapped back, its objective evaluated on
        ``qp``: one compiled pass (:func:`mcdm_pin.model.scale_kernels.unscale_answer`)."""
        c_ = np.ascontiguousarray
        n = qp.n
        if qp._P is not None:
            P, P_diag, P_factor = c_(qp._P, dtype=float), _NO_F, _NO_P
        else:
            P, P_diag, P_factor = _NO_P, c_(qp.P_diag, dtype=float), c_(qp.P_factor, dtype=float).reshape(-1, n)
        out = jit.kernels("model.scale_kernels").unscale_answer(
            self.d, self.r, float(self.obj), self.cone, c_(sol.x, dtype=float),
            _NO_F if sol.y is None else c_(sol.y, dtype=float), _NO_F if sol.z is None else c_(sol.z, dtype=float),
            _NO_ZC if sol.z_cone is None else c_(sol.z_cone, dtype=float), P, P_diag, P_factor,
            c_(qp.c, dtype=float), float(qp.r))
        return sol.but(x=out.x, objective=float(out.objective), y=None if sol.y is None else out.y,
                       z=None if sol.z is None else out.z, z_cone=None if sol.z_cone is None else out.z_cone)


def _outside(v: float) -> bool:
    return not 1.0 / SPREAD <= v <= SPREAD


def _factor_arrays(qp: QPData, f_scale) -> tuple:
    """:func:`mcdm_pin.model.kernels.scale_factors`' problem arguments (no copies: an assembled
    problem's arrays are C-ordered floats)."""
    c, A, b, lb, ub, G, g = qp.kernel_arrays()[:7]
    c_ = np.ascontiguousarray
    n = qp.n
    structured = qp.structured
    P = c_(qp._P, dtype=float) if qp._P is not None else _NO_P
    P_diag = c_(qp.P_diag, dtype=float) if structured else np.zeros(n)
    P_factor = c_(qp.P_factor, dtype=float).reshape(-1, n) if structured else np.zeros((0, n))
    fs = _NO_F if f_scale is None else c_(np.broadcast_to(np.asarray(f_scale, dtype=float), (n,)))
    return A, b, lb, ub, c, P, P_diag, P_factor, bool(structured), G, g, fs


def scaling_factors(qp: QPData, f_scale: np.ndarray | None = None, force: bool = False) -> Scaling | None:
    """The factors of the module docstring, or ``None`` when all lie within ``SPREAD`` of one (and
    ``force`` is false): one compiled pass (:func:`mcdm_pin.model.kernels.scale_factors`, compiled or
    not: mcdm_pin/jit.py), without copying the problem. The numpy code below it is the reference
    the kernel is tested against (``tests/test_warm_fast.py``), reached only where a test switches
    the kernels off."""
    m, n = qp.A.shape
    if jit.ready():
        args = _factor_arrays(qp, f_scale)
        scaled, d, r, obj, cone = jit.kernels("model.kernels").scale_factors(*args, bool(force), float(SPREAD))
        return Scaling(d, r, float(obj), cone) if scaled else None
    absA = np.abs(qp.A) if m else None
    ruiz = m and (spread(qp.A) > SPREAD or f_scale is not None)
    if ruiz:
        r, d = equilibrate(qp.A) if spread(qp.A) > SPREAD else (np.ones(m), np.ones(n))
        if f_scale is not None:
            d = d * _pow2(np.asarray(f_scale, dtype=float))
        rows = (absA * d[None, :]).max(axis=1, initial=0.0) * r
    else:
        r, d = None, 1.0
        rows = absA.max(axis=1, initial=0.0) if m else np.zeros(0)
    # the variables' unit: the size the equations ask for (|b_i| / max_j |A_ij|), at least the
    # geometric middle of the bounds (the positive lower bounds alone when there is no limit: a limit
    # is often far above the forces that occur). An instant that asks for no force (the 2-link arm at
    # rest) then gets the same unit whatever the robot's scale: with the lower bound as the unit,
    # links of 1e-6 kg put the bounds at 1 and 1e6 and Clarabel stopped with InsufficientProgress
    # where the unscaled robot solves. A negative lower bound is a limit like an upper bound (an
    # actuator's -U <= tau <= U): the thoracoscapular model's reserves, U up to 5e6 N m, as a unit
    # put the muscles' forces at 1e-5
    with np.errstate(invalid="ignore", divide="ignore"):
        lb, ub = qp.lb / d, qp.ub / d
        unit = float(lb[np.isfinite(lb) & (lb > 0)].max(initial=0.0))
        limits = np.abs(np.concatenate([lb[np.isfinite(lb) & (lb < 0)], ub[np.isfinite(ub) & (ub != 0)]]))
        if unit > 0 and len(limits) and float(limits.min()) > unit:
            unit = float(np.sqrt(unit * float(limits.min())))
        if m:
            need = np.abs(qp.b * (1.0 if r is None else r))[rows > 0] / rows[rows > 0]
            unit = max(unit, float(need.max(initial=0.0)))
    u = float(_pow2(unit)) if unit > 0 and _outside(unit) else 1.0
    d = d * u
    rows = rows * u
    row_f = np.where((rows > 0) & ((rows < 1 / SPREAD) | (rows > SPREAD)), _pow2(np.where(rows > 0, rows, 1.0)), 1.0)
    r = (np.ones(m) if r is None else r) / row_f
    scalar = np.ndim(d) == 0
    # the objective's size: each variable at its unit, or at its largest bound where that is smaller.
    # (Ruiz gives a cable that the equations barely see (moment arms ~1e-7 m) a unit of 4e6 N; at its
    # 500 N limit its scaled range is 1e-4, and the objective sized at 4e6 N made the scaled optimum
    # 3.5e-11, below the interior-point method's gap floor: tests/test_properties.py)
    with np.errstate(invalid="ignore"):
        bound = np.maximum(np.abs(qp.lb), np.abs(qp.ub))
    reach = np.minimum(np.full(n, d) if scalar else d, np.where(np.isfinite(bound), bound, np.inf))
    if qp._P is not None:
        size = float(np.abs(reach[:, None] * qp.P * reach[None, :]).max(initial=0.0))
    else:
        size = max(float(np.abs(qp.P_diag * reach * reach).max(initial=0.0)),
                   float(((qp.P_factor * reach[None, :]) ** 2).sum(axis=0).max(initial=0.0)))
    size = max(size, float(np.abs(qp.c * reach).max(initial=0.0)), 1e-300)
    obj = float(_pow2(size)) if _outside(size) else 1.0
    cone_s = np.ones(len(qp.cones))
    if qp.cones:
        G, g = qp.cone_arrays()[:2]
        sizes = np.abs(G).max(axis=(1, 2)) * u if scalar else np.abs(G * d[None, None, :]).max(axis=(1, 2))
        sizes = np.maximum(np.maximum(sizes, np.abs(g).max(axis=1)), 1e-300)
        cone_s = np.where((sizes < 1 / SPREAD) | (sizes > SPREAD), 1.0 / _pow2(sizes), 1.0)
    if not force and u == 1.0 and (scalar or np.all(d == 1.0)) and np.all(r == 1.0) and obj == 1.0 \
            and np.all(cone_s == 1.0):
        return None
    return Scaling(np.full(n, d) if scalar else d, r, obj, cone_s)


def apply_scaling(qp: QPData, s: Scaling) -> QPData:
    """The scaled copy of ``qp`` (module docstring). Its cones' stacked arrays are scaled as a whole
    and its cones' constants (names, angles, bases) carried over, not stacked again from the cones."""
    c_ = np.ascontiguousarray
    n = qp.n
    c, A, b, lb, ub, G0, g0 = qp.kernel_arrays()[:7]
    structured = qp.P_factor is not None
    P = c_(qp.P, dtype=float) if not structured or qp._P is not None else _NO_P
    P_diag = _NO_F if qp.P_diag is None else c_(qp.P_diag, dtype=float)
    P_factor = c_(qp.P_factor, dtype=float).reshape(-1, n) if structured else _NO_P
    nw = _NO_F if qp.norm_weight is None else c_(qp.norm_weight, dtype=float)
    out = jit.kernels("model.scale_kernels").scale_qp(c, A, b, lb, ub, P, P_diag, P_factor, G0, g0, nw,
                                                       s.d, s.r, float(s.obj), s.cone)
    return _scaled_copy(qp, out, s.obj)


def _scaled_copy(qp: QPData, out, obj: float) -> QPData:
    """The :class:`QPData` of ``qp``'s scaled arrays ``out`` (:class:`~mcdm_pin.model.kernel_structs.ScaledQP`;
    ``obj``: the objective's factor)."""
    cones = [ConeData(cn.joint, out.G[k], out.g[k], cn.axis, cn.angle_deg, cn.basis) for k, cn in enumerate(qp.cones)]
    structured = qp.P_factor is not None
    # (the kernel's arrays are C-ordered floats of the problem's shapes: the copy's compiled view as it
    # would make it, and the unscaled axes, tangents and bases as the problem has them; its stacked
    # cones are that view's last five)
    ka = (out.c, out.A, out.b, out.lb, out.ub, out.G, out.g) + qp.kernel_arrays()[7:]
    return QPData(out.P if out.P.shape[0] else None, out.c, qp.r / obj, out.A, out.b, out.lb, out.ub, cones,
                  P_diag=out.P_diag if qp.P_diag is not None else None, P_factor=out.P_factor if structured else None,
                  norm_weight=out.norm_weight, cone_arrays=ka[5:], cone_consts=qp.cone_consts(), kernel_arrays=ka)


def _well_scaled(arrays: tuple) -> bool:
    """The one-pass test that a structured problem needs no scaling (its every factor would be one),
    on its :func:`_factor_arrays`."""
    A, b, lb, ub, c, _, P_diag, P_factor, _, G, g, _ = arrays
    return not jit.kernels("model.kernels").needs_scaling(A, b, lb, ub, P_diag, P_factor, c, G, g, float(SPREAD))


def scale_problem(qp: QPData, f_scale: np.ndarray | None = None, force: bool = False, quick: bool = True):
    """``(scaled QPData, Scaling)``, or ``(qp, None)`` when no scaling is needed: the factors and the
    scaled copy in one compiled call (:func:`mcdm_pin.model.scale_kernels.scale_instant`), after the
    one-pass test that a well-scaled instant needs none (its usual answer; ``quick=False`` leaves
    it to the compiled call, which makes it too: one call fewer for an instant that likely needs
    scaling, the same factors)."""
    if not jit.ready():  # (a test's numpy references)
        s = scaling_factors(qp, f_scale, force)
        return (qp, None) if s is None else (apply_scaling(qp, s), s)
    arrays = _factor_arrays(qp, f_scale)
    A, b, lb, ub, c, P, P_diag, P_factor, structured, G, g, fs = arrays
    if quick and structured and not force and f_scale is None and _well_scaled(arrays):
        return qp, None
    c_ = np.ascontiguousarray
    if not structured:  # (the copy scales the problem's own diagonal, if it gives one)
        P_diag = _NO_F if qp.P_diag is None else c_(qp.P_diag, dtype=float)
    nw = _NO_F if qp.norm_weight is None else c_(qp.norm_weight, dtype=float)
    out = jit.kernels("model.scale_kernels").scale_instant(A, b, lb, ub, c, P, P_diag, P_factor, structured, G, g,
                                                           fs, nw, bool(force), float(SPREAD))
    if not out.scaled:
        return qp, None
    s = Scaling(out.d, out.r, float(out.obj), out.cone)
    return _scaled_copy(qp, out.qp, s.obj), s


class ScaledSolver(Solver):
    """Wrap a back-end: solve the scaled problem, return the unscaled answer (module docstring).

    Args:
        inner: the back-end (a :class:`~mcdm_pin.solvers.Solver`).
    """

    def __init__(self, inner: Solver):
        self.inner = inner
        self.name = inner.name
        # whether the last instant was scaled: along a trajectory the next one usually is too, and
        # then the one-pass test for a well-scaled instant is left to the compiled call that
        # scales (scale_problem's ``quick``: one call fewer, the same factors)
        self._scaled_last = False
        # the last optimal instant's factors (:meth:`_scale`)
        self._kept: Scaling | None = None

    def fresh(self) -> "ScaledSolver":
        return ScaledSolver(self.inner.fresh())

    def reset(self) -> None:
        self.inner.reset()
        self._scaled_last = False
        self._kept = None

    def needs_scaling(self, qp: QPData) -> bool:
        return scale_problem(qp)[1] is not None

    def _scale(self, qp: QPData) -> tuple[QPData, Scaling | None, bool]:
        """``(scaled copy, its Scaling, kept)`` or ``(qp, None, False)``. Along a trajectory the
        factors (powers of two) of consecutive instants are nearly always the same: the last optimal
        instant's are kept where they fit ``qp`` and the copy they make passes the one-pass test of
        a well-scaled problem (:func:`mcdm_pin.model.kernels.needs_scaling`; structured problems),
        which makes no factors (about a third of their cost on MyoSuite's arm). Else this instant's
        own (:func:`scale_problem`). Kept factors equal to the instant's own give the same copy to
        the bit; others a copy with the same solutions, whose answer differs within rounding."""
        kept = self._kept
        if kept is not None and qp.structured and kept.fits(qp):
            scaled = apply_scaling(qp, kept)
            if _well_scaled(_factor_arrays(scaled, None)):
                return scaled, kept, True
        scaled, scaling = scale_problem(qp, quick=not self._scaled_last)
        return scaled, scaling, False

    def solve(self, qp: QPData) -> Solution:
        scaled, scaling, kept = self._scale(qp)
        self._scaled_last = scaling is not None
        sol = self.inner.solve(scaled)
        self._kept = scaling if sol.status == OPTIMAL else None
        if scaling is None:
            return sol
        sol = scaling.unscale(qp, sol)
        if sol.status == INACCURATE and kept:  # the instant's own factors next, as without kept ones
            return self.solve(qp)
        if sol.status == INACCURATE:
            # the scaling can hurt: equilibrating a column 1e7 smaller than the others (a hybrid arm
            # held straight, PlanarSnakeArm at q = 0) spread the scaled Hessian over 14 decades and
            # every back-end's answer failed the KKT check, where the problem as given solves. Then
            # the problem as given is tried, and its answer kept if it passes
            plain = self.inner.solve(qp)
            if plain.status == OPTIMAL:
                return plain
        return sol

    def __getattr__(self, name):  # expose the inner back-end's settings and helpers
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)
