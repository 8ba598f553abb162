r"""MuJoCo's muscle model as the force range of a cable: at one instant a muscle pulls with a tension
between its passive force and its passive plus its fully activated force.

A MuJoCo muscle actuator (``dyntype``, ``gaintype`` and ``biastype`` all ``muscle``) on a tendon of
length :math:`\ell` (m) and velocity :math:`\dot\ell` (m/s) with gear :math:`g` has the actuator length
:math:`L = g\,\ell` and velocity :math:`V = g\,\dot\ell`, and the actuator force (N, negative: it pulls)

.. math:: F_{act} = -F_0\,F_L(l)\,F_V(v)\,a \;-\; F_0^{p}\,F_P(l^{p}),

with the activation :math:`a`. The transmission's moment is :math:`g\,J_\ell` (:math:`J_\ell` the
tendon's Jacobian), so the generalized force :math:`g J_\ell^T F_{act}` is that of a cable pulling with
the tension (N, >= 0)

.. math:: t = -g\,F_{act} = \underbrace{g F_0^{p} F_P(l^{p})}_{\text{passive}}
          + \underbrace{g F_0 F_L(l) F_V(v)}_{\text{gain}}\; a .

Normalisation (``range`` :math:`[r_0, r_1]`, ``lengthrange`` :math:`[L_{r0}, L_{r1}]` in actuator units,
i.e. metres times the gear; :math:`\epsilon` = ``mjMINVAL`` = 1e-15 guards every division as MuJoCo does):

.. math:: L_{opt} = \frac{L_{r1}-L_{r0}}{\max(\epsilon, r_1-r_0)},\quad
          l = r_0 + \frac{L-L_{r0}}{\max(\epsilon, L_{opt})},\quad
          v = \frac{V}{\max(\epsilon, L_{opt}\,v_{max})} .

Curves (dimensionless; :math:`a_l = (l_{min}+1)/2`, :math:`b_l = (1+l_{max})/2`, :math:`y = f_{vmax}-1`):

- :math:`F_L(l)`: 0 outside :math:`[l_{min}, l_{max}]`; :math:`x^2/2` with
  :math:`x = (l-l_{min})/(a_l-l_{min})` up to :math:`a_l`; :math:`1-x^2/2` with :math:`x=(1-l)/(1-a_l)` up
  to 1; :math:`1-x^2/2` with :math:`x=(l-1)/(b_l-1)` up to :math:`b_l`; :math:`x^2/2` with
  :math:`x=(l_{max}-l)/(l_{max}-b_l)` up to :math:`l_{max}`. Maximum 1 at :math:`l = 1`.
- :math:`F_V(v)`: 0 for :math:`v \le -1` (shortening at :math:`v_{max}` or faster); :math:`(v+1)^2` up
  to 0; :math:`f_{vmax} - (y-v)^2/y` up to :math:`y`; :math:`f_{vmax}` beyond (lengthening).
- :math:`F_P(l)` (with the bias parameters): 0 for :math:`l \le 1`; :math:`f_{pmax}\,x^2/2` with
  :math:`x=(l-1)/(b_l-1)` up to :math:`b_l`; :math:`f_{pmax}(1/2 + (l-b_l)/(b_l-1))` beyond (linear,
  unbounded).

:math:`F_0` is ``force`` when it is >= 0, else ``scale / max(eps, actuator_acc0)`` (MuJoCo 4.0 keeps the
``-1`` in the compiled ``gainprm[2]`` and divides at run time; :func:`from_mujoco` resolves it).

The gain parameters (``gainprm``: range, force, scale, lmin, lmax, vmax, fvmax) drive the active term
and the bias parameters (``biasprm``: range, force, scale, lmax, fpmax) the passive one. MJCF's
``<muscle>`` writes the same numbers into both, but the two can differ (MyoSuite's ``myoarm_r``:
``SUPSP``), so the passive side keeps its own F0 and normalised length (:math:`F_0^p`, :math:`l^p`,
``bias_*``).

The activation holds within ``[act_min, act_max]``: ``[0, 1]`` (``mju_muscleDynamics`` clamps the control
to it and drives the activation towards it), narrowed by ``ctrlrange`` and ``actrange`` where limited.
With ``actearly`` MuJoCo evaluates the force at the next step's activation; the relation is the same.

API: :func:`from_mujoco` (a compiled ``MjModel`` -> :class:`MuscleParams` and tendon ids),
:func:`normalised`, :func:`normalised_passive`, :func:`fl`, :func:`fv`, :func:`fp` (the curves),
:func:`force_range` (-> :class:`MuscleState`; :func:`tension_state` without the checks),
:func:`activation` (its inverse), :func:`length_slopes`
(with :func:`dfl`, :func:`dfp`).

The curves and the tension range are computed by the compiled kernels of
:mod:`mcdm_pin.model.muscle_kernels` (plain Python before ``mcdm-pin compile``: one implementation).

This follows ``mju_muscleGainLength``, ``mju_muscleGain``, ``mju_muscleBias`` and
``mju_muscleDynamics`` (``src/engine/engine_util_misc.c``) and ``mj_fwdActuation``
(``src/engine/engine_forward.c``) of google-deepmind/mujoco, checked against MuJoCo 4.0.0's
``actuator_force`` in ``tests/test_muscles.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from functools import cached_property
from typing import NamedTuple

import numpy as np

from ..exceptions import ModelError, StateError
from ..settings import DEFAULT

MINVAL = 1e-15
"""MuJoCo's ``mjMINVAL``: the floor of every denominator of the muscle curves."""


@dataclass(frozen=True)
class MuscleParams:
    """The parameters of m muscles, arrays over muscles (shape ``(m,)`` unless said).

    Attributes:
        names: the actuators' names.
        range: (m, 2) the operating range ``[r0, r1]`` of the normalised length (MJCF ``range``).
        force: F0, N (actuator units), resolved: ``scale / acc0`` where the MJCF gave ``force < 0``.
        scale: MJCF ``scale`` (used only when ``force < 0``).
        lmin, lmax: ends of the active force-length curve, normalised length.
        vmax: shortening velocity at which the active force vanishes, in optimal lengths per second.
        fpmax: scale of the passive curve (from ``biasprm``): ``F_P`` is ``fpmax/2`` at
            ``l = (1 + bias_lmax)/2`` and ``1.5 fpmax`` at ``bias_lmax`` (MuJoCo's code).
        fvmax: active force per F0 at fast lengthening.
        bias_range, bias_force, bias_lmax: the passive term's range, F0 (resolved) and lmax
            (``biasprm``; equal to ``range``, ``force``, ``lmax`` for an MJCF ``<muscle>``).
        lengthrange: (m, 2) the actuator's length range, m times the gear (``actuator_lengthrange``).
        gear: ``g`` (> 0): actuator length = g * tendon length, tendon tension = -g * actuator force.
        ctrlrange, actrange: (m, 2) MuJoCo's ranges, ``[-inf, inf]`` where not limited.
        act_min, act_max: the activations the muscle can hold: ``[0, 1]`` (``mju_muscleDynamics``
            clamps the control to it), within ``ctrlrange`` when ``ctrllimited`` (the activation settles
            at the clamped control) and within ``actrange`` when ``actlimited``.
    """

    names: tuple
    range: np.ndarray
    force: np.ndarray
    scale: np.ndarray
    lmin: np.ndarray
    lmax: np.ndarray
    vmax: np.ndarray
    fpmax: np.ndarray
    fvmax: np.ndarray
    bias_range: np.ndarray
    bias_force: np.ndarray
    bias_lmax: np.ndarray
    lengthrange: np.ndarray
    gear: np.ndarray
    ctrlrange: np.ndarray
    actrange: np.ndarray
    act_min: np.ndarray
    act_max: np.ndarray

    def __post_init__(self):
        m = len(self.names)
        object.__setattr__(self, "names", tuple(str(n) for n in self.names))
        for f in fields(self):
            if f.name == "names":
                continue
            arr = np.array(getattr(self, f.name), dtype=float)
            shape = (m, 2) if f.name in ("range", "bias_range", "lengthrange", "ctrlrange", "actrange") else (m,)
            if arr.shape != shape:
                raise ModelError(f"MuscleParams.{f.name}: expected shape {shape} for {m} muscles, got {arr.shape}")
            if f.name not in ("ctrlrange", "actrange") and not np.all(np.isfinite(arr)):
                raise ModelError(f"MuscleParams.{f.name}: expected finite values, got {arr.tolist()}")
            arr.setflags(write=False)
            object.__setattr__(self, f.name, arr)
        for name, bad, expected in (
                ("force", self.force < 0, "F0 >= 0 (a muscle pulls)"),
                ("bias_force", self.bias_force < 0, "F0 >= 0 (a muscle pulls)"),
                ("gear", self.gear <= 0, "gear > 0 (a negative gear makes the muscle push)"),
                ("act_max", self.act_min > self.act_max, "act_min <= act_max")):
            if np.any(bad):
                raise ModelError(f"MuscleParams.{name} of {self._which(bad)}: expected {expected}")

    def _which(self, mask) -> str:
        return ", ".join(repr(self.names[i]) for i in np.flatnonzero(mask))

    @property
    def size(self) -> int:
        return len(self.names)

    @property
    def optimal_length(self) -> np.ndarray:
        """``L_opt`` (m,), actuator units (m times the gear): the length one normalised unit spans."""
        return _optimal_length(self.lengthrange, self.range)

    @cached_property
    def _curves(self) -> "_Curves":
        """The curves' constants (:class:`_Curves`), computed once (the normalisation below and the
        kernels' table, :attr:`kernel_table`)."""
        return _curves(self)

    @cached_property
    def kernel_table(self) -> np.ndarray:
        """The constants of :mod:`mcdm_pin.model.muscle_kernels` (its ``N_ROWS`` rows, m columns;
        read-only), from :attr:`_curves`' expressions."""
        return _kernel_table(self)

    def length_at(self, l) -> np.ndarray:
        """Tendon lengths (m) at normalised lengths ``l`` (broadcast over muscles; inverse of the map)."""
        return (self.lengthrange[:, 0] + (np.asarray(l, dtype=float) - self.range[:, 0])
                * np.maximum(MINVAL, self.optimal_length)) / self.gear


class MuscleState(NamedTuple):
    """The tension range of m muscles at one state (arrays of the inputs' shape, N on the tendon).

    ``f = passive + gain * a``; ``f_min``/``f_max`` at ``a_min``/``a_max``. Where ``gain`` is 0 (outside
    ``[lmin, lmax]`` or shortening at ``vmax`` or faster) the range collapses to the passive force.
    """

    passive: np.ndarray
    gain: np.ndarray
    f_min: np.ndarray
    f_max: np.ndarray
    a_min: np.ndarray
    a_max: np.ndarray


class MujocoMuscles(NamedTuple):
    """What :func:`from_mujoco` found: the muscles, their tendons and the actuators it left aside.

    Attributes:
        params: :class:`MuscleParams` of the muscle actuators, in actuator order.
        tendon_ids: (m,) MuJoCo tendon id of each muscle.
        actuator_ids: (m,) MuJoCo actuator id of each muscle.
        skipped: ``(name, reason)`` of every actuator that is not a muscle.
    """

    params: MuscleParams
    tendon_ids: np.ndarray
    actuator_ids: np.ndarray
    skipped: tuple


# --------------------------------------------------------------------------------- curves


def _optimal_length(lengthrange, rng):
    return (lengthrange[:, 1] - lengthrange[:, 0]) / np.maximum(MINVAL, rng[:, 1] - rng[:, 0])


class _Curves(NamedTuple):
    """Constants of the curves of m muscles, each (m,) and computed with the very expressions the
    curves used per call (so every result is the same to the bit)."""

    r0: np.ndarray  # range[:, 0]
    bias_r0: np.ndarray  # bias_range[:, 0]
    lr0: np.ndarray  # lengthrange[:, 0]
    lopt: np.ndarray  # max(eps, L_opt)
    bias_lopt: np.ndarray  # max(eps, L_opt^p)
    vden: np.ndarray  # max(eps, L_opt vmax)
    fl_a: np.ndarray  # (lmin + 1) / 2
    fl_b: np.ndarray  # (1 + lmax) / 2
    fl_d: tuple  # the four denominators of F_L's pieces
    fv_y: np.ndarray  # fvmax - 1
    fv_d: np.ndarray  # max(eps, fvmax - 1)
    fp_b: np.ndarray  # (1 + bias_lmax) / 2
    fp_w: np.ndarray  # max(eps, fp_b - 1)
    fp_half: np.ndarray  # fpmax * 0.5
    passive_scale: np.ndarray  # gear * bias_force
    gain_scale: np.ndarray  # gear * force


def _curves(p: MuscleParams) -> _Curves:
    a = 0.5 * (p.lmin + 1)
    b = 0.5 * (1 + p.lmax)
    y = p.fvmax - 1
    fp_b = 0.5 * (1 + p.bias_lmax)
    out = _Curves(
        r0=p.range[:, 0].copy(), bias_r0=p.bias_range[:, 0].copy(), lr0=p.lengthrange[:, 0].copy(),
        lopt=np.maximum(MINVAL, _optimal_length(p.lengthrange, p.range)),
        bias_lopt=np.maximum(MINVAL, _optimal_length(p.lengthrange, p.bias_range)),
        vden=np.maximum(MINVAL, p.optimal_length * p.vmax), fl_a=a, fl_b=b,
        fl_d=(np.maximum(MINVAL, a - p.lmin), np.maximum(MINVAL, 1 - a), np.maximum(MINVAL, b - 1),
              np.maximum(MINVAL, p.lmax - b)),
        fv_y=y, fv_d=np.maximum(MINVAL, y), fp_b=fp_b, fp_w=np.maximum(MINVAL, fp_b - 1),
        fp_half=p.fpmax * 0.5, passive_scale=p.gear * p.bias_force, gain_scale=p.gear * p.force)
    for arr in (*out[:8], *out.fl_d, *out[9:]):
        arr.setflags(write=False)
    return out


def _lengths(params: MuscleParams, tendon_lengths, what: str) -> np.ndarray:
    x = np.asarray(tendon_lengths, dtype=float)
    if x.shape[-1:] != (params.size,):
        raise StateError(f"muscles: {what} must have last axis of size {params.size} (one per muscle), "
                         f"got shape {x.shape}")
    if not np.isfinite(x).all():
        raise StateError(f"muscles: {what} must be finite, got {np.count_nonzero(~np.isfinite(x))} non-finite")
    return x


def normalised(params: MuscleParams, tendon_lengths, tendon_velocities):
    """Normalised length ``l`` and velocity ``v`` of the active term (arrays with last axis m).

    Args:
        tendon_lengths: tendon lengths, m (``data.ten_length`` of the muscles' tendons).
        tendon_velocities: their rates, m/s (``data.ten_velocity``).
    Returns:
        ``l = r0 + (g*ell - Lr0)/L_opt`` (1 at the optimal length) and ``v = g*ell_dot/(L_opt*vmax)``
        (-1 when shortening at vmax).
    """
    ell = _lengths(params, tendon_lengths, "tendon_lengths")
    ell_dot = _lengths(params, tendon_velocities, "tendon_velocities")
    k = params._curves
    l = k.r0 + (params.gear * ell - k.lr0) / k.lopt
    v = params.gear * ell_dot / k.vden
    return l, v


def normalised_passive(params: MuscleParams, tendon_lengths) -> np.ndarray:
    """Normalised length ``l^p`` of the passive term (with ``bias_range``; equals ``l`` of
    :func:`normalised` when ``bias_range == range``)."""
    ell = _lengths(params, tendon_lengths, "tendon_lengths")
    k = params._curves
    return k.bias_r0 + (params.gear * ell - k.lr0) / k.bias_lopt


def _kernel_table(p: MuscleParams) -> np.ndarray:
    from . import muscle_kernels as mk

    k = p._curves
    t = np.empty((mk.N_ROWS, p.size))
    for row, value in ((mk.R0, k.r0), (mk.BIAS_R0, k.bias_r0), (mk.LR0, k.lr0), (mk.LOPT, k.lopt),
                       (mk.BIAS_LOPT, k.bias_lopt), (mk.VDEN, k.vden), (mk.GEAR, p.gear), (mk.LMIN, p.lmin),
                       (mk.LMAX, p.lmax), (mk.FL_A, k.fl_a), (mk.FL_B, k.fl_b), (mk.FL_D1, k.fl_d[0]),
                       (mk.FL_D2, k.fl_d[1]), (mk.FL_D3, k.fl_d[2]), (mk.FL_D4, k.fl_d[3]), (mk.FV_Y, k.fv_y),
                       (mk.FV_D, k.fv_d), (mk.FVMAX, p.fvmax), (mk.FP_B, k.fp_b), (mk.FP_W, k.fp_w),
                       (mk.FP_HALF, k.fp_half), (mk.FPMAX, p.fpmax), (mk.PASSIVE_SCALE, k.passive_scale),
                       (mk.GAIN_SCALE, k.gain_scale), (mk.ACT_MIN, p.act_min), (mk.ACT_MAX, p.act_max)):
        t[row] = value
    t.setflags(write=False)
    return t


def _kernels():
    from .. import jit

    return jit.kernels("model.muscle_kernels")  # compiled or not: mcdm_pin/jit.py


def _curve(params: MuscleParams, x, which: int) -> np.ndarray:
    """Curve ``which`` (0 F_L, 1 F_V, 2 F_P) at ``x`` (last axis m, or broadcast to it): the
    compiled curves of :mod:`mcdm_pin.model.muscle_kernels`."""
    x = np.asarray(x, dtype=float)
    shape = np.broadcast_shapes(x.shape, (params.size,))
    rows = np.ascontiguousarray(np.broadcast_to(x, shape).reshape(-1, params.size))
    return _kernels().curves(rows, which, params.kernel_table).reshape(shape)


def fl(params: MuscleParams, l) -> np.ndarray:
    """Active force-length curve ``F_L(l)`` in [0, 1] (``mju_muscleGainLength``)."""
    return _curve(params, l, 0)


def fv(params: MuscleParams, v) -> np.ndarray:
    """Force-velocity curve ``F_V(v)`` in [0, fvmax] (the velocity curve of ``mju_muscleGain``)."""
    return _curve(params, v, 1)


def fp(params: MuscleParams, l) -> np.ndarray:
    """Passive force-length curve ``F_P(l)`` >= 0 per F0 (``mju_muscleBias``; ``bias_lmax``, ``fpmax``).

    ``l`` is the passive normalised length (:func:`normalised_passive`)."""
    return _curve(params, l, 2)


def force_range(params: MuscleParams, tendon_lengths, tendon_velocities) -> MuscleState:
    """Tension range on the tendons (N) at lengths (m) and velocities (m/s), last axis m.

    ``passive = g F0^p F_P(l^p)``, ``gain = g F0 F_L(l) F_V(v)``, ``f_min = passive + gain * act_min``,
    ``f_max = passive + gain * act_max``. Where ``gain`` is 0 the range collapses to the passive force
    (``f_min == f_max``): the muscle can neither add nor withhold tension there.

    OpenSim's muscles (:class:`~mcdm_pin.model.muscles_osim.OpenSimMuscles`, the other kind of
    ``params``) answer with their own curves, in the same :class:`MuscleState`.
    """
    if not isinstance(params, MuscleParams):  # the OpenSim kind
        return params.force_range(tendon_lengths, tendon_velocities)
    ell = _lengths(params, tendon_lengths, "tendon_lengths")
    ell_dot = _lengths(params, tendon_velocities, "tendon_velocities")
    if ell.shape != ell_dot.shape:
        ell, ell_dot = np.broadcast_arrays(ell, ell_dot)
    return tension_state(params, ell, ell_dot)


def tension_state(params: MuscleParams, ell: np.ndarray, ell_dot: np.ndarray) -> MuscleState:
    """:func:`force_range` of checked float arrays of one shape (last axis m): one call of the
    compiled :func:`mcdm_pin.model.muscle_kernels.tension_range` (OpenSim's muscles: their own curves,
    :meth:`~mcdm_pin.model.muscles_osim.OpenSimMuscles.force_range`)."""
    if not isinstance(params, MuscleParams):  # the OpenSim kind
        return params.force_range(ell, ell_dot)
    shape, m = ell.shape, params.size
    c_ = np.ascontiguousarray  # (one compiled specialisation: C-ordered 2-D float arrays)
    out = _kernels().tension_range(c_(ell.reshape(-1, m)), c_(ell_dot.reshape(-1, m)), params.kernel_table)
    passive, gain, f_min, f_max = out.reshape((4,) + shape)
    if len(shape) == 1:
        return MuscleState(passive, gain, f_min, f_max, params.act_min, params.act_max)
    return MuscleState(passive, gain, f_min, f_max, np.broadcast_to(params.act_min, shape),
                       np.broadcast_to(params.act_max, shape))


def dfl(params: MuscleParams, l) -> np.ndarray:
    """Slope ``dF_L/dl`` of :func:`fl` (0 outside ``[lmin, lmax]``; continuous: ``F_L`` is C1)."""
    l = np.asarray(l, dtype=float)
    lmin, lmax = params.lmin, params.lmax
    a = 0.5 * (lmin + 1)
    b = 0.5 * (1 + lmax)
    d1, d2 = np.maximum(MINVAL, a - lmin), np.maximum(MINVAL, 1 - a)
    d3, d4 = np.maximum(MINVAL, b - 1), np.maximum(MINVAL, lmax - b)
    inside = (lmin <= l) & (l <= lmax)
    return np.select([~inside, l <= a, l <= 1, l <= b],
                     [0.0, (l - lmin) / d1 / d1, (1 - l) / d2 / d2, -(l - 1) / d3 / d3], -(lmax - l) / d4 / d4)


def dfp(params: MuscleParams, l) -> np.ndarray:
    """Slope ``dF_P/dl`` of :func:`fp` at passive normalised lengths ``l`` (C1: 0, linear, constant)."""
    l = np.asarray(l, dtype=float)
    w = np.maximum(MINVAL, 0.5 * (1 + params.bias_lmax) - 1)
    return np.select([l <= 1, l <= 0.5 * (1 + params.bias_lmax)], [0.0, params.fpmax * (l - 1) / w / w],
                     params.fpmax / w)


def length_slopes(params: MuscleParams, tendon_lengths, tendon_velocities):
    """Derivatives of ``passive`` and ``gain`` (:func:`force_range`) with respect to the tendon length,
    N/m, at fixed tendon velocity: ``g F0^p F_P'(l^p) g / L_opt^p`` and ``g F0 F_L'(l) F_V(v) g / L_opt``.

    (``v`` does not depend on the length: ``L_opt`` is a constant of the muscle.) The range's ends move
    with ``d passive + a * d gain`` at ``a = act_min``, ``act_max``.
    """
    l, v = normalised(params, tendon_lengths, tendon_velocities)
    lp = normalised_passive(params, tendon_lengths)
    dl = params.gear / np.maximum(MINVAL, params.optimal_length)
    dlp = params.gear / np.maximum(MINVAL, _optimal_length(params.lengthrange, params.bias_range))
    d_passive = params.gear * params.bias_force * dfp(params, lp) * dlp
    d_gain = params.gear * params.force * dfl(params, l) * fv(params, v) * dl
    return d_passive, d_gain


def activation(state: MuscleState, f, bound_abs: float = DEFAULT.bound_abs) -> np.ndarray:
    """Activation ``a = (f - passive) / gain`` that makes tensions ``f`` (N) at ``state``.

    Not clipped: ``f`` outside ``[f_min, f_max]`` gives ``a`` outside ``[a_min, a_max]``. Where ``gain``
    is 0 every activation gives the passive force: the answer is ``a_min`` (the least effort) when ``f``
    is within ``bound_abs`` (N; the answer check's, :attr:`~mcdm_pin.settings.Settings.bound_abs`) of it, NaN otherwise (no activation makes that tension).
    """
    f = np.asarray(f, dtype=float)
    if f.shape != np.shape(state.gain):
        raise StateError(f"muscles: tensions f must have shape {np.shape(state.gain)}, got {f.shape}")
    gain = np.asarray(state.gain)
    zero = gain == 0
    if not zero.any():  # (every muscle's tension moves with its activation: the formula alone)
        return (f - state.passive) / gain
    a = (f - state.passive) / np.where(zero, 1.0, gain)
    at_passive = np.abs(f - state.passive) <= bound_abs
    return np.where(zero, np.where(at_passive, state.a_min, np.nan), a)


# --------------------------------------------------------------------------------- MuJoCo


def _is_muscle(mj, i) -> bool:
    import mujoco

    return (mj.actuator_gaintype[i] == mujoco.mjtGain.mjGAIN_MUSCLE
            or mj.actuator_biastype[i] == mujoco.mjtBias.mjBIAS_MUSCLE)


def _refusal(mj, i) -> str | None:
    """Why muscle actuator ``i`` cannot be a cable, or None."""
    import mujoco

    trn = mujoco.mjtTrn(mj.actuator_trntype[i])
    if trn != mujoco.mjtTrn.mjTRN_TENDON:
        return f"its transmission is {trn.name}; only muscles on tendons (mjTRN_TENDON) become cables"
    kinds = (mujoco.mjtDyn(mj.actuator_dyntype[i]).name, mujoco.mjtGain(mj.actuator_gaintype[i]).name,
             mujoco.mjtBias(mj.actuator_biastype[i]).name)
    if kinds != ("mjDYN_MUSCLE", "mjGAIN_MUSCLE", "mjBIAS_MUSCLE"):
        return f"dyntype/gaintype/biastype are {'/'.join(kinds)}; expected muscle/muscle/muscle"
    if mj.actuator_plugin[i] >= 0:
        return "it is an actuator plugin"
    if mj.actuator_gear[i, 0] <= 0:
        return f"its gear is {mj.actuator_gear[i, 0]!r}; expected > 0 (a muscle pulls on its tendon)"
    if mj.actuator_forcelimited[i]:
        return ("it is forcelimited: the clamp of the force makes the activation ambiguous; "
                "remove forcerange")
    if mj.tendon_actfrclimited[mj.actuator_trnid[i, 0]]:
        return "its tendon has actuatorfrcrange: the tendon's clamp is not modelled; remove it"
    lr = mj.actuator_lengthrange[i]
    if not lr[1] > lr[0]:
        return f"its lengthrange {lr.tolist()} is empty; let the compiler compute it (lengthrange mode)"
    for prm, side in ((mj.actuator_gainprm[i], "gainprm"), (mj.actuator_biasprm[i], "biasprm")):
        if not prm[1] > prm[0]:
            return f"its {side} range {prm[:2].tolist()} is empty; expected range[0] < range[1]"
    return None


def _f0(force, scale, acc0):
    return np.where(force < 0, scale / np.maximum(MINVAL, acc0), force)


def from_mujoco(mj) -> MujocoMuscles:
    """The muscle actuators of a compiled ``mujoco.MjModel`` as cables' tension models.

    Reads every actuator with a muscle gain or bias; non-muscle actuators are listed in ``skipped``.

    Raises:
        ModelError: naming the actuator, for a muscle that cannot be a cable (on a joint or a site,
            mixed dyn/gain/bias types, gear <= 0, forcelimited, tendon actuatorfrcrange, empty
            lengthrange or range) or a muscle whose activation range is empty.
    """
    muscles, skipped = [], []
    for i in range(mj.nu):
        name = mj.actuator(i).name or f"actuator {i}"
        if not _is_muscle(mj, i):
            skipped.append((name, "not a muscle (neither gaintype nor biastype is muscle)"))
            continue
        why = _refusal(mj, i)
        if why is not None:
            raise ModelError(f"MuJoCo actuator {name!r}: {why}")
        muscles.append(i)
    ids = np.array(muscles, dtype=int)
    g, b = mj.actuator_gainprm[ids], mj.actuator_biasprm[ids]
    acc0 = mj.actuator_acc0[ids]
    inf = np.array([-np.inf, np.inf])
    ctrl = np.where(mj.actuator_ctrllimited[ids, None].astype(bool), mj.actuator_ctrlrange[ids], inf)
    act = np.where(mj.actuator_actlimited[ids, None].astype(bool), mj.actuator_actrange[ids], inf)
    names = tuple(mj.actuator(int(i)).name or f"actuator {i}" for i in ids)
    act_min = np.maximum.reduce([np.zeros(len(ids)), ctrl[:, 0], act[:, 0]])
    act_max = np.minimum.reduce([np.ones(len(ids)), ctrl[:, 1], act[:, 1]])
    empty = act_min > act_max
    if np.any(empty):
        bad = ", ".join(repr(names[k]) for k in np.flatnonzero(empty))
        raise ModelError(f"MuJoCo actuators {bad}: [0, 1], ctrlrange and actrange leave no activation")
    params = MuscleParams(
        names=names, range=g[:, 0:2], force=_f0(g[:, 2], g[:, 3], acc0), scale=g[:, 3], lmin=g[:, 4],
        lmax=g[:, 5], vmax=g[:, 6], fpmax=b[:, 7], fvmax=g[:, 8], bias_range=b[:, 0:2],
        bias_force=_f0(b[:, 2], b[:, 3], acc0), bias_lmax=b[:, 5], lengthrange=mj.actuator_lengthrange[ids],
        gear=mj.actuator_gear[ids, 0], ctrlrange=ctrl, actrange=act, act_min=act_min, act_max=act_max)
    return MujocoMuscles(params, mj.actuator_trnid[ids, 0].astype(int), ids, tuple(skipped))
