r"""OpenSim's functions of one coordinate, evaluated as OpenSim evaluates them, with two derivatives.

Every function here maps a number ``x`` (a coordinate value, rad or m) to ``(f(x), f'(x), f''(x))``
(:meth:`value`). They drive a ``CustomJoint``'s ``TransformAxis``, a ``CoordinateCouplerConstraint``
and (in :mod:`mcdm_pin.osim.paths`) moving path points.

- ``Constant``: ``f = c``.
- ``LinearFunction`` (``coefficients a b``): ``f = a x + b``.
- ``MultiplierFunction`` (``function``, ``scale s``): ``f = s g(x)``.
- ``PolynomialFunction`` (``coefficients c_n ... c_0``, highest power first as OpenSim writes them).
- ``SimmSpline`` (``x``, ``y``): the cubic spline of SIMM (Forsythe, Malcolm and Moler's ``spline``):
  continuous second derivative; at each end, with four points or more, the third derivative of the
  cubic through the four end points (divided differences), with three a zero end correction, with
  two the straight line; outside ``[x_0, x_{n-1}]`` the straight line with the end slope
  (``f'' = 0``).
- ``NaturalCubicSpline`` (``x``, ``y``): despite its name, OpenSim computes it exactly as
  ``SimmSpline`` (same end conditions, same straight-line extrapolation), and so does this module.
- ``PiecewiseLinearFunction`` (``x``, ``y``): straight segments; outside, the end segment continued;
  ``f'' = 0``.

Anything else is refused (:func:`read_function`) with the element's tag.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exceptions import ModelError

_TINY = 1e-14  # SIMM's smallest knot spacing


@dataclass(frozen=True)
class Constant:
    c: float

    def value(self, x):
        return self.c, 0.0, 0.0


@dataclass(frozen=True)
class Linear:
    a: float
    b: float

    def value(self, x):
        return self.a * x + self.b, self.a, 0.0


@dataclass(frozen=True)
class Multiplier:
    scale: float
    inner: object

    def value(self, x):
        f, d1, d2 = self.inner.value(x)
        return self.scale * f, self.scale * d1, self.scale * d2


@dataclass(frozen=True)
class Polynomial:
    coefficients: tuple  # highest power first

    def value(self, x):
        f = d1 = d2 = 0.0
        for c in self.coefficients:  # Horner for f, f', f''
            d2 = d2 * x + 2.0 * d1
            d1 = d1 * x + f
            f = f * x + c
        return f, d1, d2


class _Cubic:
    """Piecewise cubic ``y_k + b_k t + c_k t^2 + d_k t^3`` with ``t = x - x_k`` on ``[x_k, x_{k+1}]``."""

    def __init__(self, x, y, b, c, d, linear_outside: bool):
        self.x, self.y, self.b, self.c, self.d = x, y, b, c, d
        self.linear_outside = linear_outside

    def value(self, x):
        xs, n = self.x, len(self.x)
        if self.linear_outside and (x < xs[0] or x > xs[-1]):
            k = 0 if x < xs[0] else n - 1
            return self.y[k] + (x - xs[k]) * self.b[k], self.b[k], 0.0
        k = int(np.clip(np.searchsorted(xs, x, side="right") - 1, 0, n - 2))
        t = x - xs[k]
        b, c, d = self.b[k], self.c[k], self.d[k]
        return self.y[k] + t * (b + t * (c + t * d)), b + t * (2.0 * c + 3.0 * t * d), 2.0 * c + 6.0 * t * d


def simm_spline(x, y) -> _Cubic:
    """SIMM's spline through ``(x, y)`` (module docstring): a tridiagonal solve for the second
    derivatives with the divided-difference end conditions, then each segment's coefficients."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    n = len(x)
    b, c, d = np.zeros(n), np.zeros(n), np.zeros(n)
    if n == 2:
        b[:] = (y[1] - y[0]) / max(_TINY, x[1] - x[0])
        return _Cubic(x, y, b, c, d, True)
    h = np.maximum(_TINY, np.diff(x))  # d_i of the classical routine: the spacing
    d[:n - 1] = h
    c[1] = (y[1] - y[0]) / h[0]
    for i in range(1, n - 1):
        b[i] = 2.0 * (h[i - 1] + h[i])
        c[i + 1] = (y[i + 1] - y[i]) / h[i]
        c[i] = c[i + 1] - c[i]
    b[0], b[n - 1] = -h[0], -h[n - 2]
    c[0] = c[n - 1] = 0.0
    if n > 3:
        c0 = c[2] / max(_TINY, x[3] - x[1]) - c[1] / max(_TINY, x[2] - x[0])
        cn = c[n - 2] / max(_TINY, x[n - 1] - x[n - 3]) - c[n - 3] / max(_TINY, x[n - 2] - x[n - 4])
        c[0] = c0 * h[0] ** 2 / max(_TINY, x[3] - x[0])
        c[n - 1] = -cn * h[n - 2] ** 2 / max(_TINY, x[n - 1] - x[n - 4])
    for i in range(1, n):  # forward elimination (off-diagonal d[i-1] = h[i-1])
        t = d[i - 1] / b[i - 1]
        b[i] -= t * d[i - 1]
        c[i] -= t * c[i - 1]
    c[n - 1] /= b[n - 1]
    for i in range(n - 2, -1, -1):  # back substitution
        c[i] = (c[i] - d[i] * c[i + 1]) / b[i]
    b[n - 1] = (y[n - 1] - y[n - 2]) / h[n - 2] + h[n - 2] * (c[n - 2] + 2.0 * c[n - 1])
    for i in range(n - 1):
        b[i] = (y[i + 1] - y[i]) / h[i] - h[i] * (c[i + 1] + 2.0 * c[i])
        d[i] = (c[i + 1] - c[i]) / h[i]
        c[i] *= 3.0
    c[n - 1] *= 3.0
    d[n - 1] = d[n - 2]
    return _Cubic(x, y, b, c, d, True)


def piecewise_linear(x, y) -> _Cubic:
    """Straight segments through ``(x, y)``, continued beyond the ends."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    b = np.zeros(len(x))
    b[:-1] = np.diff(y) / np.diff(x)
    b[-1] = b[-2]
    zeros = np.zeros(len(x))
    return _Cubic(x, y, b, zeros, zeros, False)


_SPLINES = {"SimmSpline": simm_spline, "NaturalCubicSpline": simm_spline,
            "PiecewiseLinearFunction": piecewise_linear}
FUNCTION_TAGS = ("Constant", "LinearFunction", "MultiplierFunction", "PolynomialFunction", *_SPLINES)


def _numbers(el, tag: str, where: str) -> tuple:
    node = el.find(tag)
    if node is None or node.text is None or not node.text.split():
        raise ModelError(f"{where}: <{el.tag}> has no <{tag}> numbers")
    try:
        values = tuple(float(t) for t in node.text.split())
    except ValueError:
        raise ModelError(f"{where}: <{el.tag}><{tag}> must hold numbers, got {node.text.strip()!r}") from None
    if not all(np.isfinite(values)):
        raise ModelError(f"{where}: <{el.tag}><{tag}> must hold finite numbers, got {node.text.strip()!r}")
    return values


def read_function(el, where: str):
    """The function of the XML element ``el`` (one of :data:`FUNCTION_TAGS`); ``where`` names the
    element for messages (file, owner)."""
    tag = el.tag
    if tag == "Constant":
        return Constant(_numbers(el, "value", where)[0])
    if tag == "LinearFunction":
        coef = _numbers(el, "coefficients", where)
        if len(coef) != 2:
            raise ModelError(f"{where}: <LinearFunction> expects 2 coefficients (slope, intercept), got {coef}")
        return Linear(*coef)
    if tag == "MultiplierFunction":
        holder = el.find("function")
        inner = [c for c in (holder if holder is not None else [])]
        if len(inner) != 1:
            raise ModelError(f"{where}: <MultiplierFunction> expects one function inside <function>")
        scale = _numbers(el, "scale", where)[0] if el.find("scale") is not None else 1.0
        return Multiplier(scale, read_function(inner[0], where))
    if tag == "PolynomialFunction":
        return Polynomial(_numbers(el, "coefficients", where))
    if tag in _SPLINES:
        x, y = _numbers(el, "x", where), _numbers(el, "y", where)
        if len(x) != len(y) or len(x) < 2:
            raise ModelError(f"{where}: <{tag}> expects as many x as y values, at least 2; got {len(x)} and {len(y)}")
        if np.any(np.diff(x) <= 0):
            raise ModelError(f"{where}: <{tag}> x values must increase strictly, got {x}")
        return _SPLINES[tag](x, y)
    raise ModelError(f"{where}: function <{tag}> is not supported; expected one of {', '.join(FUNCTION_TAGS)}")


def is_identity(f) -> bool:
    """Whether ``f(x) = x`` exactly (a unit-slope line through 0, possibly inside multipliers)."""
    scale = 1.0
    while isinstance(f, Multiplier):
        scale, f = scale * f.scale, f.inner
    return isinstance(f, Linear) and scale * f.a == 1.0 and scale * f.b == 0.0


def constant_value(f):
    """The value of a constant function (``Constant``, possibly inside multipliers), else ``None``."""
    scale = 1.0
    while isinstance(f, Multiplier):
        scale, f = scale * f.scale, f.inner
    return scale * f.c if isinstance(f, Constant) else None
