r"""OpenSim's muscles (``Millard2012EquilibriumMuscle``, ``DeGrooteFregly2016Muscle``) with a rigid tendon
as the force range of a cable: the OpenSim kind of :mod:`mcdm_pin.model.muscles` (same
:class:`~mcdm_pin.model.muscles.MuscleState`, same use as per-instant bounds).

At muscle-tendon length :math:`\ell` (m) and lengthening speed :math:`\dot\ell` (m/s), with optimal
fiber length :math:`l_o`, tendon slack length :math:`l_s`, pennation :math:`\alpha_o` at :math:`l_o`,
maximum contraction velocity :math:`v_{max}` (:math:`l_o`/s), maximum isometric force :math:`F_0`:

- rigid tendon, constant fiber thickness :math:`h = l_o \sin\alpha_o`: the fiber length along the
  tendon is :math:`\ell - l_s`, the fiber length :math:`l = \sqrt{h^2 + (\ell - l_s)^2}`,
  :math:`\cos\alpha = (\ell - l_s)/l`, the fiber velocity :math:`\dot l = \dot\ell \cos\alpha`;
  normalised :math:`\tilde l = l/l_o`, :math:`\tilde v = \dot l/(l_o v_{max})`;
- tendon tension :math:`t = F_0 (a f_L(\tilde l) f_V(\tilde v) + f_P(\tilde l) + \beta\tilde v)\cos\alpha`
  with the activation :math:`a` and the fiber damping :math:`\beta`: affine in :math:`a`, so
  ``passive`` :math:`= F_0 (f_P + \beta\tilde v)\cos\alpha` and ``gain`` :math:`= F_0 f_L f_V \cos\alpha`.

**Millard2012EquilibriumMuscle** (``ignore_tendon_compliance``): :math:`f_L`, :math:`f_V`, :math:`f_P` are
OpenSim's quintic Bézier curves (``SmoothSegmentedFunctionFactory``: active force-length, force-velocity,
fiber force-length, from the curves' properties; linear beyond their ends), evaluated as OpenSim does
(Newton's method on the Bézier parameter, OpenSim to 2.2e-14 in ``x``, we to machine precision). With
damping (``fiber_damping`` >= 0.001, OpenSim's default 0.1) OpenSim sets the active curve's
``minimum_value`` to 0 and the force-velocity slopes at ``vmax`` to 0, as we do. The fiber is clamped
at its minimum length (the larger of ``min_norm_active_fiber_length`` :math:`l_o` and the pennation
model's :math:`h/\sin\alpha_{max}`, or :math:`0.01 l_o` without pennation): at or below it while
shortening the muscle has no force; a tendon shorter than its slack length (a clamped fiber) has
:math:`\tilde v = 0`, :math:`f_V = 1`. With a rigid tendon OpenSim saturates the fiber force at 0
(the damping cannot push): ``f_min``, ``f_max`` are clipped at 0 where ``passive + gain a < 0``.
The activation lies in ``[minimum_activation, 1]``.

**DeGrooteFregly2016Muscle** (``ignore_tendon_compliance``): the analytic curves of De Groote et al.
(2016) as OpenSim 4.6 writes them: :math:`f_L` the sum of three Gaussian-like terms in
:math:`x = (\tilde l - 1)/w + 1` (``active_force_width_scale`` :math:`w`), :math:`f_V = d_1
\ln(d_2\tilde v + d_3 + \sqrt{(d_2\tilde v + d_3)^2 + 1}) + d_4`, :math:`f_P = (e^{k(\tilde l - 1)/e_0} -
o)/(e^k - o)`, :math:`o = e^{k(0.2 - 1)/e_0}`, :math:`k = 4` (0 with ``ignore_passive_fiber_force``),
no clamps; the activation in ``[min_control, max_control]`` (0 and 1 by default).

**Thelen2003Muscle** (rigid tendon as OpenSim's ``calcInextensibleTendonActiveFiberForce``, the
force Static Optimization uses; OpenSim 4.6 refuses ``ignore_tendon_compliance`` on a Thelen muscle):
the fiber as above with OpenSim's fixed-width pennation model (fiber length at least
:math:`l_{min} = h/\sin\alpha_{max}`; no force at or below it), :math:`f_L = e^{-(\tilde l - 1)^2/K_a}`,
:math:`f_P = (e^{K_p(\tilde l - 1)/e_0} - 1)/(e^{K_p} - 1)` for :math:`\tilde l > 1` (else 0), no
damping. The force-velocity multiplier is the inverse of Thelen's (2003) eqs. 6-7 as OpenSim writes
them (``calcdlceN``), with :math:`c = 0.25 + 0.75 a`, ``Af`` :math:`A_f`, ``Flen`` :math:`F_{len}`,
:math:`k = (2 + 2/A_f)/(F_{len} - 1)`, threshold :math:`\theta` (``fv_linear_extrap_threshold``):
:math:`f_V = (c + \tilde v)/(c - \tilde v/A_f)` for :math:`-c < \tilde v \le 0`, 0 for
:math:`\tilde v \le -c`; :math:`f_V = (c + k F_{len}\tilde v)/(c + k\tilde v)` for
:math:`0 < f_V < \theta F_{len}`, and beyond OpenSim's linear extrapolation of :math:`\tilde v(f_V)`
at :math:`\theta F_{len}`. OpenSim finds this :math:`f_V` by Newton's method (``calcfvInv``,
tolerance 1e-6 in :math:`\tilde v`, then one more step); we solve it in closed form.

:math:`f_V` depends on the activation, so the tension
:math:`t(a) = F_0 (a f_L f_V(\tilde v, a) + f_P)\cos\alpha` is *not* affine in :math:`a` (it is where
:math:`\tilde v = 0`). The range is exact: ``f_min`` :math:`= t(a_{min})`, ``f_max`` :math:`= t(1)`
(:math:`t` increases with :math:`a`). ``passive`` and ``gain`` are the chord through these two
ends, ``passive + gain a``, which the solver takes as the tension at activation :math:`a` (in
between it differs from :math:`t(a)`: :meth:`OpenSimMuscles.thelen_chord_error`, and
docs/opensim.md); :meth:`OpenSimMuscles.tension` is the exact :math:`t(a)`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import jit
from ..exceptions import ModelError, StateError

SIGNIFICANT = 1.0 / 2 ** 46  # SimTK::SignificantReal (eps^(7/8)) for doubles: about 1.9e-14
MIN_DAMPING = 0.001  # Millard's MIN_NONZERO_DAMPING_COEFFICIENT


# ------------------------------------------------------------------ quintic Bézier curves (OpenSim)

def _corner(x0, y0, dydx0, x1, y1, dydx1, curviness):
    """SegmentedQuinticBezierToolkit::calcQuinticBezierCornerControlPoints: six x and six y."""
    if abs(dydx0 - dydx1) > math.sqrt(np.finfo(float).eps):
        xc = (y1 - y0 - x1 * dydx1 + x0 * dydx0) / (dydx0 - dydx1)
    else:
        xc = (x1 + x0) / 2
    yc = (xc - x1) * dydx1 + y1
    x0m, y0m = x0 + curviness * (xc - x0), y0 + curviness * (yc - y0)
    x1m, y1m = x1 + curviness * (xc - x1), y1 + curviness * (yc - y1)
    return (x0, x0m, x0m, x1m, x1m, x1), (y0, y0m, y0m, y1m, y1m, y1)


def _scale_curviness(c):
    return 0.1 + 0.8 * c


_BINOM5 = np.array([1.0, 5.0, 10.0, 10.0, 5.0, 1.0])


@dataclass(frozen=True)
class BezierCurve:
    """OpenSim's ``SmoothSegmentedFunction``: quintic Bézier segments (control points ``px``, ``py``
    (k, 6)) on ``[x0, x1]``, lines of slopes ``dydx0``, ``dydx1`` through ``(x0, y0)``, ``(x1, y1)``
    beyond."""

    px: np.ndarray
    py: np.ndarray
    x0: float
    x1: float
    y0: float
    y1: float
    dydx0: float
    dydx1: float

    def __call__(self, x) -> np.ndarray:
        """The curve at abscissae ``x`` (the kernel of :func:`_evaluate`, one row per abscissa)."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        n = len(x)
        rows = BezierCurve(*(np.ascontiguousarray(np.broadcast_to(np.asarray(getattr(self, f), dtype=float),
                                                                  (n,) + np.shape(getattr(self, f))))
                             for f in ("px", "py", "x0", "x1", "y0", "y1", "dydx0", "dydx1")))
        return _evaluate(_tables(rows), x)


def _curve(points, x0, x1, y0, y1, dydx0, dydx1) -> BezierCurve:
    return BezierCurve(np.array([p[0] for p in points]), np.array([p[1] for p in points]), x0, x1, y0, y1,
                       dydx0, dydx1)


def active_force_length_curve(x0, x1, x3, ylow, dydx, x2=1.0, curviness=1.0) -> BezierCurve:
    """``createFiberActiveForceLengthCurve(x0, x1, x2 = 1, x3, ylow, dydx, curviness = 1)``."""
    c = _scale_curviness(curviness)
    dx = 0.05 * x2
    xs = x2 - dx
    y0, dydx0 = 0.0, 0.0
    y1 = 1 - dydx * (xs - x1)
    dydx01 = 1.25 * (y1 - y0) / (x1 - x0)
    x01, y01 = x0 + 0.5 * (x1 - x0), y0 + 0.5 * (y1 - y0)
    x1s, y1s = x1 + 0.5 * (xs - x1), y1 + 0.5 * (1 - y1)
    y2, dydx2, y3, dydx3 = 1.0, 0.0, 0.0, 0.0
    x23 = (x2 + dx) + 0.5 * (x3 - (x2 + dx))
    y23 = y2 + 0.5 * (y3 - y2)
    dydx23 = (y3 - y2) / ((x3 - dx) - (x2 + dx))
    pts = [_corner(x0, ylow, dydx0, x01, y01, dydx01, c), _corner(x01, y01, dydx01, x1s, y1s, dydx, c),
           _corner(x1s, y1s, dydx, x2, y2, dydx2, c), _corner(x2, y2, dydx2, x23, y23, dydx23, c),
           _corner(x23, y23, dydx23, x3, ylow, dydx3, c)]
    return _curve(pts, x0, x3, ylow, ylow, 0.0, 0.0)


def force_velocity_curve(fmax_e, dydx_c, dydx_near_c, dydx_iso, dydx_e, dydx_near_e, conc_curv,
                         ecc_curv) -> BezierCurve:
    """``createFiberForceVelocityCurve``."""
    cc, ce = _scale_curviness(conc_curv), _scale_curviness(ecc_curv)
    xc, yc, xnc = -1.0, 0.0, -0.9
    ync = yc + 0.5 * dydx_near_c * (xnc - xc) + 0.5 * dydx_c * (xnc - xc)
    xi, yi, xe, ye, xne = 0.0, 1.0, 1.0, fmax_e, 0.9
    yne = ye + 0.5 * dydx_near_e * (xne - xe) + 0.5 * dydx_e * (xne - xe)
    pts = [_corner(xc, yc, dydx_c, xnc, ync, dydx_near_c, cc), _corner(xnc, ync, dydx_near_c, xi, yi, dydx_iso, cc),
           _corner(xi, yi, dydx_iso, xne, yne, dydx_near_e, ce), _corner(xne, yne, dydx_near_e, xe, ye, dydx_e, ce)]
    return _curve(pts, xc, xe, yc, ye, dydx_c, dydx_e)


def fiber_force_length_curve(e_zero, e_iso, k_low, k_iso, curviness) -> BezierCurve:
    """``createFiberForceLengthCurve``."""
    c = _scale_curviness(curviness)
    x_zero, x_iso = 1 + e_zero, 1 + e_iso
    dx = min(0.1 * (1.0 / k_iso), 0.1 * (x_iso - x_zero))
    x_low = x_zero + dx
    x_foot = x_zero + 0.5 * (x_low - x_zero)
    y_low = k_low * (x_low - x_foot)
    pts = [_corner(x_zero, 0.0, 0.0, x_low, y_low, k_low, c), _corner(x_low, y_low, k_low, x_iso, 1.0, k_iso, c)]
    return _curve(pts, x_zero, x_iso, 0.0, 1.0, 0.0, k_iso)


# ------------------------------------------------------------------ De Groote & Fregly (2016)

_B = ((0.8150671134243542, 1.055033428970575, 0.162384573599574, 0.063303448465465),
      (0.433004984392647, 0.716775413397760, -0.029947116970696, 0.200356847296188),
      (0.1, 1.0, 0.353553390593274, 0.0))
_D1, _D2, _D3, _D4 = -0.3211346127989808, -8.149, -0.374, 0.8825327733249912
_KPE, _MIN_NORM_FIBER = 4.0, 0.2


def degroote_fl(l, width=1.0):
    x = (np.asarray(l, dtype=float) - 1.0) / width + 1.0
    return sum(b1 * np.exp(-0.5 * (x - b2) ** 2 / (b3 + b4 * x) ** 2) for b1, b2, b3, b4 in _B)


def degroote_fv(v):
    t = _D2 * np.asarray(v, dtype=float) + _D3
    return _D1 * np.log(t + np.sqrt(t * t + 1.0)) + _D4


def degroote_fp(l, e0=0.6):
    offset = math.exp(_KPE * (_MIN_NORM_FIBER - 1.0) / e0)
    return (np.exp(_KPE * (np.asarray(l, dtype=float) - 1.0) / e0) - offset) / (math.exp(_KPE) - offset)


# ------------------------------------------------------------------ Thelen (2003)

def thelen_fv(v, a, af, flen, threshold):
    """Thelen's force-velocity multiplier at normalised fiber velocity ``v`` and activation ``a``: the
    inverse of OpenSim's ``calcdlceN`` (module docstring), in closed form; arrays broadcast."""
    v, a = np.asarray(v, dtype=float), np.asarray(a, dtype=float)
    c = 0.25 + 0.75 * a
    k = (2.0 + 2.0 / af) / (flen - 1.0)
    f_star = threshold * flen
    v_e = c * (f_star - 1.0) / (k * (flen - f_star))           # v at f_V = theta F_len
    slope_e = c * (flen - 1.0) / (k * (flen - f_star) ** 2)  # dv/df_V there
    with np.errstate(divide="ignore", invalid="ignore"):
        conc = np.maximum((c + v) / (c - v / af), 0.0)
        ecc = (c + k * flen * v) / (c + k * v)
    return np.where(v <= 0, np.where(v <= -c, 0.0, conc),
                    np.where(v < v_e, ecc, f_star + (v - v_e) / slope_e))


def thelen_fl(l, k_active):
    return np.exp(-(np.asarray(l, dtype=float) - 1.0) ** 2 / k_active)


def thelen_fp(l, k_passive, e0):
    l = np.asarray(l, dtype=float)
    return np.where(l > 1.0, (np.exp(k_passive * (l - 1.0) / e0) - 1.0) / (np.exp(k_passive) - 1.0), 0.0)


# ------------------------------------------------------------------ the muscles

KINDS = ("Millard2012EquilibriumMuscle", "DeGrooteFregly2016Muscle", "Thelen2003Muscle")


@dataclass(frozen=True)
class OpenSimMuscle:
    """One OpenSim muscle with a rigid tendon (module docstring). Lengths in metres, ``vmax`` in optimal
    fiber lengths per second, ``alpha0`` radians, ``f0`` newtons; ``curves``: Millard's
    ``(f_L, f_V, f_P)`` :class:`BezierCurve`\\ s, De Groote's ``(width, e0, passive)``, or Thelen's
    ``(KshapeActive, KshapePassive, FmaxMuscleStrain, Af, Flen, fv_linear_extrap_threshold)``;
    ``min_fiber``: Millard's and Thelen's minimum fiber length (m)."""

    name: str
    kind: str
    f0: float
    lo: float
    ls: float
    alpha0: float
    vmax: float
    damping: float
    a_min: float
    a_max: float
    curves: tuple
    max_pennation: float = math.acos(0.1)
    min_fiber: float = 0.0


def _stack(curves) -> BezierCurve:
    """Curves of one shape (as many segments each) as one :class:`BezierCurve` whose fields carry a
    leading muscle axis, evaluated by :func:`_evaluate` on one abscissa per muscle."""
    return BezierCurve(np.stack([c.px for c in curves]), np.stack([c.py for c in curves]),
                       *(np.array([getattr(c, f) for c in curves]) for f in ("x0", "x1", "y0", "y1", "dydx0", "dydx1")))


def _concat(curves) -> BezierCurve:
    """Stacked curves (:func:`_stack`) one after the other along the muscle axis, as one, so that
    :func:`_evaluate` solves them in one pass. Curves with fewer segments repeat their last one (same
    end point, so :func:`_evaluate` picks the same control points)."""
    k = max(c.px.shape[1] for c in curves)
    pad = lambda P: np.concatenate([P, np.repeat(P[:, -1:], k - P.shape[1], axis=1)], axis=1)  # noqa: E731
    return BezierCurve(np.concatenate([pad(c.px) for c in curves]), np.concatenate([pad(c.py) for c in curves]),
                       *(np.concatenate([getattr(c, f) for c in curves])
                         for f in ("x0", "x1", "y0", "y1", "dydx0", "dydx1")))


_GRID = np.linspace(0.0, 1.0, 129)  # Bézier parameters of the tables that start Newton's iteration


def _grid(c) -> np.ndarray:
    """(muscles, segments, len(_GRID)) the stacked curve's abscissae ``x(u)`` at ``u = _GRID``."""
    i = np.arange(6)
    basis = _BINOM5 * (1 - _GRID[:, None]) ** (5 - i) * _GRID[:, None] ** i  # (G, 6)
    return c.px @ basis.T


def _tables(c) -> tuple:
    """The arguments of :func:`mcdm_pin.model.bezier_kernels.bezier_values` for a stacked curve
    (:func:`_stack`): control points, ends, start tables (C-ordered, built once per muscle set)."""
    ends = np.stack([c.x0, c.x1, c.y0, c.y1, c.dydx0, c.dydx1], axis=1)
    return tuple(np.ascontiguousarray(a, dtype=float) for a in (c.px, c.py, ends, _grid(c)))


def _evaluate(tables, x) -> np.ndarray:
    """A stacked curve (its :func:`_tables`) at one abscissa per row ``x``: one compiled call
    (:mod:`mcdm_pin.model.bezier_kernels`: Newton's method on the Bézier parameter from the tables'
    interpolation, OpenSim's linear extensions beyond the ends)."""
    return jit.kernels("model.bezier_kernels").bezier_values(*tables, np.ascontiguousarray(x, dtype=float))


class OpenSimMuscles:
    """The OpenSim kind of muscle parameters (:mod:`mcdm_pin.model.muscles` dispatches
    ``force_range`` to :meth:`force_range`). ``names``, ``size``, ``muscles``; the per-muscle numbers
    are also kept as arrays, and each kind's curves stacked, so that an instant costs a few numpy calls
    whatever the number of muscles."""

    def __init__(self, muscles):
        self.muscles = tuple(muscles)
        self.names = tuple(m.name for m in self.muscles)
        for m in self.muscles:
            if m.kind not in KINDS:
                raise ModelError(f"muscle {m.name!r}: kind {m.kind!r} is not modelled; expected one of {KINDS}")
            if not (m.f0 >= 0 and m.lo > 0 and m.ls >= 0 and 0 <= m.alpha0 < math.pi / 2 and m.vmax > 0
                    and 0 <= m.a_min <= m.a_max):
                raise ModelError(f"muscle {m.name!r}: expected F0 >= 0, optimal fiber length > 0, tendon slack "
                                 f"length >= 0, pennation in [0, pi/2), vmax > 0 and 0 <= a_min <= a_max")
        for f in ("f0", "lo", "ls", "alpha0", "vmax", "damping", "a_min", "a_max", "max_pennation", "min_fiber"):
            setattr(self, f, np.array([getattr(m, f) for m in self.muscles], dtype=float))
        self.millard = np.array([m.kind == KINDS[0] for m in self.muscles], dtype=bool)
        self.thelen = np.array([m.kind == KINDS[2] for m in self.muscles], dtype=bool)
        self._mi = np.flatnonzero(self.millard)
        self._di = np.flatnonzero(~self.millard & ~self.thelen)
        self._ti = np.flatnonzero(self.thelen)
        self._th = np.array([self.muscles[i].curves for i in self._ti], dtype=float).reshape(-1, 6).T
        mill = [self.muscles[i] for i in self._mi]
        self._curves = tuple(_stack([m.curves[k] for m in mill]) for k in range(3)) if mill else None
        # the three curves (active force-length, force-velocity, passive) solved as one
        self._all = _tables(_concat(self._curves)) if mill else None
        dg = [self.muscles[i] for i in self._di]
        self._dg = tuple(np.array([m.curves[k] for m in dg], dtype=float) for k in range(3))
        self.h = self.lo * np.sin(self.alpha0)
        sin_max = np.sin(self.max_pennation)
        self._pen_min = np.where(self.max_pennation > SIGNIFICANT, self.h / sin_max, 0.01 * self.lo)
        self._sin_max = sin_max
        # constants of fiber(): the pennation floor's threshold, the masks, the speed's scale
        self._floor_along = self._pen_min * np.cos(self.max_pennation)
        self._pennate = self.alpha0 > np.finfo(float).eps
        self._slack_below = self.ls - SIGNIFICANT
        self._pennated = self.millard | self.thelen
        self._speed_scale = self.lo * self.vmax
        # Millard's muscles alone: fiber() needs no kinds' masks, gathers or scatters, and
        # force_range() is one compiled call (bezier_kernels.millard_range)
        self._only_millard = bool(self.size and self.millard.all())
        # the constants of the compiled fiber and range (bezier_kernels' K_* rows)
        self._muscle_table = np.ascontiguousarray(np.array(
            [self.ls, self.h, self._pen_min, self._floor_along, self.min_fiber, self._pennate.astype(float),
             self.max_pennation, self._sin_max, self._slack_below, self.lo, self._speed_scale, self.f0,
             self.damping, self.a_min, self.a_max], dtype=float).reshape(15, self.size))

    @property
    def size(self) -> int:
        return len(self.muscles)

    def fiber(self, tendon_lengths, tendon_velocities):
        """``(l, v, cos_alpha, clamped)`` (m,) each: normalised fiber length and velocity, the cosine of
        the pennation and Millard's or Thelen's clamp (no force) at muscle-tendon lengths and speeds
        (m,)."""
        ell, ell_dot = self._checked(tendon_lengths, tendon_velocities)
        # Millard: the pennation model's floor, the fiber clamp, the pennation angle's limits (one
        # compiled pass, bezier_kernels.pennation: the same code as millard_range's)
        lf, lf_m, cos_m, dl_m, clamped = jit.kernels("model.bezier_kernels").pennation(ell, ell_dot,
                                                                                       self._muscle_table)
        clamped = clamped != 0.0
        if self._only_millard:
            return lf_m / self.lo, dl_m / self._speed_scale, cos_m, clamped
        cos_d = (ell - self.ls) / lf
        # Thelen: the same pennation model, no slack rule; no force at or below the minimum length
        pennated = self._pennated
        lf = np.where(pennated, lf_m, lf)
        cos_a = np.where(pennated, cos_m, cos_d)
        dl = np.where(self.millard, dl_m, ell_dot * cos_a)
        clamped = np.where(self.thelen, lf_m <= self._pen_min, self.millard & clamped)
        return lf / self.lo, dl / self._speed_scale, cos_a, clamped

    def _checked(self, tendon_lengths, tendon_velocities):
        """The muscle-tendon lengths and speeds as float arrays of shape (m,), or StateError."""
        ell = np.asarray(tendon_lengths, dtype=float)
        ell_dot = np.asarray(tendon_velocities, dtype=float)
        if ell.shape != (self.size,) or ell_dot.shape != (self.size,):
            raise StateError(f"muscles: expected lengths and speeds of shape ({self.size},), got {ell.shape} "
                             f"and {ell_dot.shape}")
        return ell, ell_dot

    def force_range(self, tendon_lengths, tendon_velocities):
        """The tension range (:class:`~mcdm_pin.model.muscles.MuscleState`) at one instant."""
        from .muscles import MuscleState

        if self._only_millard:  # every muscle Millard's: fiber, curves and range in one compiled call
            ell, ell_dot = self._checked(tendon_lengths, tendon_velocities)
            passive, gain, f_min, f_max = jit.kernels("model.bezier_kernels").millard_range(
                ell, ell_dot, self._muscle_table, *self._all)
            return MuscleState(passive, gain, f_min, f_max, self.a_min, self.a_max)
        l, v, cos_a, clamped = self.fiber(tendon_lengths, tendon_velocities)
        mi, di = self._mi, self._di
        fl, fv, fp = np.zeros(self.size), np.zeros(self.size), np.zeros(self.size)
        if mi.size:
            fl[mi], fv[mi], fp[mi] = _evaluate(self._all, np.concatenate([l[mi], v[mi], l[mi]])).reshape(3, -1)
        if di.size:
            width, e0, use_passive = self._dg
            x = (l[di] - 1.0) / width + 1.0
            fl[di] = sum(b1 * np.exp(-0.5 * (x - b2) ** 2 / (b3 + b4 * x) ** 2) for b1, b2, b3, b4 in _B)
            fv[di] = degroote_fv(v[di])
            offset = np.exp(_KPE * (_MIN_NORM_FIBER - 1.0) / e0)
            fp[di] = np.where(use_passive > 0, (np.exp(_KPE * (l[di] - 1.0) / e0) - offset)
                              / (math.exp(_KPE) - offset), 0.0)
        live = ~clamped
        # the range from the curves, as for Millard's alone (bezier_kernels._range_one)
        passive, gain, f_min, f_max = jit.kernels("model.bezier_kernels").tension_range(
            self._muscle_table, fl, fv, fp, np.ascontiguousarray(v, dtype=float),
            np.ascontiguousarray(cos_a, dtype=float), live, self.millard)
        ti = self._ti
        if ti.size:  # Thelen: exact ends, the chord between them (module docstring)
            fl_t, fp_t, t_lo, t_hi = self._thelen(l[ti], v[ti], cos_a[ti], live[ti], self.a_min[ti], self.a_max[ti])
            a_lo, a_hi = self.a_min[ti], self.a_max[ti]
            gain[ti] = np.where(a_hi > a_lo, (t_hi - t_lo) / np.where(a_hi > a_lo, a_hi - a_lo, 1.0), 0.0)
            passive[ti] = t_lo - gain[ti] * a_lo
            f_min[ti], f_max[ti] = t_lo, t_hi
        return MuscleState(passive, gain, f_min, f_max, self.a_min, self.a_max)

    def _thelen(self, l, v, cos_a, live, *activations):
        """Thelen's ``f_L``, ``f_P`` and exact tensions ``t(a)`` (N) at each of ``activations``, for the
        Thelen muscles (arguments restricted to them)."""
        k_a, k_p, e0, af, flen, thr = self._th
        f0 = self.f0[self._ti]
        fl, fp = thelen_fl(l, k_a), thelen_fp(l, k_p, e0)
        out = []
        for a in activations:
            a = np.clip(a, self.a_min[self._ti], 1.0)  # OpenSim's clampActivation
            out.append(np.where(live, f0 * (a * fl * thelen_fv(v, a, af, flen, thr) + fp) * cos_a, 0.0))
        return (fl, fp, *out)

    def tension(self, tendon_lengths, tendon_velocities, activations):
        """Every muscle's exact tension (N) at activations ``a`` (m,) (clamped to ``[a_min, a_max]``):
        ``passive + gain a`` for Millard and De Groote (and 0 where Millard's fiber force would be
        negative), Thelen's non-affine ``t(a)`` for Thelen's."""
        a = np.clip(np.asarray(activations, dtype=float), self.a_min, self.a_max)
        st = self.force_range(tendon_lengths, tendon_velocities)
        out = st.passive + st.gain * a
        out = np.where(self.millard, np.maximum(out, 0.0), out)
        ti = self._ti
        if ti.size:
            l, v, cos_a, clamped = self.fiber(tendon_lengths, tendon_velocities)
            out[ti] = self._thelen(l[ti], v[ti], cos_a[ti], ~clamped[ti], a[ti])[2]
        return out

    def thelen_chord_error(self, tendon_lengths, tendon_velocities, activations):
        """``(passive + gain a) - t(a)`` (N) for every muscle (0 but for Thelen's): what the solver's
        affine tension makes of Thelen's at activations ``a`` (m,)."""
        st = self.force_range(tendon_lengths, tendon_velocities)
        a = np.clip(np.asarray(activations, dtype=float), self.a_min, self.a_max)
        return np.where(self.thelen, st.passive + st.gain * a - self.tension(tendon_lengths, tendon_velocities, a),
                        0.0)
