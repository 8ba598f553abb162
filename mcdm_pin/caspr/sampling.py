r"""CASPR's joint trajectories sampled exactly as CASPR samples them, then written in our coordinates.

**Time grid** (``JointTrajectory.*Create``): segment p is sampled at MATLAB's ``t_p:dt:t_{p+1}``; its
spline runs from the first to the **last sample** of that grid (so a segment whose duration is not a
multiple of dt ends at rest at its last sample, and the next starts at ``t_{p+1}``); the first sample of
every segment after the first is dropped (a junction is kept once, with the earlier segment's rates).

**Splines** (``Spline.m``), per coordinate: quintic (end positions, rates, accelerations), cubic (end
positions and rates), linear, parabolic blend (CASPR's formulas and branch tests ``t < t_s + t_b``,
``t < t_e - t_b``). **Rotations** (``SphericalEulerXYZ``/``SphericalFixedXYZ`` and the orientation of
``SpatialEulerXYZ``): :math:`R(t) = R_s \exp(\theta(t)[k]_\times)` with :math:`R_s^T R_e = \exp(\theta_{se}
[k]_\times)` and :math:`\theta` the same spline from 0 to :math:`\theta_{se}` (zero end rates), so the
child-frame angular velocity and acceleration are :math:`\dot\theta k` and :math:`\ddot\theta k`.

**Our coordinates.** Scalar coordinates are copied. An Euler triple's angles come from :math:`R` by
CASPR's formulas (``rotation_matrix_to_angles``) and their rates from :math:`\omega = S(q)\dot q`,
:math:`\dot\omega = S\ddot q + \dot S\dot q`, exactly. (CASPR evaluates the rates by formulas that divide
by :math:`\sin\alpha` or :math:`\sin\gamma` and falls back to a backward difference where that is 0/0,
and rounds angles and rates to 10 decimals; we do neither.) A free joint takes the position, a rotation
vector :math:`\log R`, and Pinocchio's velocity :math:`(R^T\dot p, \omega)` and acceleration
:math:`(R^T\ddot p - \omega\times R^T\dot p, \dot\omega)`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..exceptions import CasprError
from ..trajectory import SINGULAR_DET
from .trajectories import CasprTrajectory, matlab_colon


# --------------------------------------------------------------------------------- rotations
def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def euler_rotation(convention: str, angles) -> np.ndarray:
    """``xyz``: Rx(a) Ry(b) Rz(g) (S_EULER_XYZ); ``fixed``: Rz(g) Ry(b) Rx(a) (S_FIXED_XYZ)."""
    a, b, g = angles
    return _rx(a) @ _ry(b) @ _rz(g) if convention == "xyz" else _rz(g) @ _ry(b) @ _rx(a)


def euler_angles(convention: str, R: np.ndarray) -> np.ndarray:
    """CASPR's ``rotation_matrix_to_angles`` (without its rounding to 10 decimals), R (N, 3, 3)."""
    if convention == "xyz":
        b = np.arcsin(np.clip(R[:, 0, 2], -1, 1))
        g = -np.arctan2(R[:, 0, 1], R[:, 0, 0])
        a = -np.arctan2(R[:, 1, 2], R[:, 2, 2])
    else:
        b = -np.arcsin(np.clip(R[:, 2, 0], -1, 1))
        g = np.arctan2(R[:, 1, 0], R[:, 0, 0])
        a = np.arctan2(R[:, 2, 1], R[:, 2, 2])
    return np.stack([a, b, g], axis=1)


def euler_S(convention: str, angles, rates=None):
    """CASPR's S (child-frame angular velocity = S q_dot) and, with ``rates``, dS/dt."""
    a, b, g = angles
    sa, ca, sb, cb, sg, cg = np.sin(a), np.cos(a), np.sin(b), np.cos(b), np.sin(g), np.cos(g)
    if convention == "xyz":
        S = np.array([[cb * cg, sg, 0], [-cb * sg, cg, 0], [sb, 0, 1]])
        if rates is None:
            return S
        _, bd, gd = rates
        dS = bd * np.array([[-sb * cg, 0, 0], [sb * sg, 0, 0], [cb, 0, 0]]) \
            + gd * np.array([[-cb * sg, cg, 0], [-cb * cg, -sg, 0], [0, 0, 0]])
        return S, dS
    S = np.array([[1, 0, -sb], [0, ca, sa * cb], [0, -sa, ca * cb]])
    if rates is None:
        return S
    ad, bd, _ = rates
    dS = ad * np.array([[0, 0, 0], [0, -sa, ca * cb], [0, -ca, -sa * cb]]) \
        + bd * np.array([[0, 0, -cb], [0, 0, -sa * sb], [0, 0, -ca * sb]])
    return S, dS


# ------------------------------------------------------------------------------------ splines
# end-state (Hermite) bases on s in [0, 1], as polynomial coefficients in powers of s: the spline is
# sum_i c_i h_i(s) with c = (x0, T v0, T^2 a0, x1, T v1, T^2 a1) (quintic), (x0, T v0, x1, T v1) (cubic);
# they are exactly 0 or 1 at the ends, so every segment meets its end states to the last bit (a
# set-point segment of one time step holds still at both samples)
_HERMITE = {
    "quintic": np.array([[1, 0, 0, -10, 15, -6], [0, 1, 0, -6, 8, -3], [0, 0, 0.5, -1.5, 1.5, -0.5],
                         [0, 0, 0, 10, -15, 6], [0, 0, 0, -4, 7, -3], [0, 0, 0, 0.5, -1, 0.5]]),
    "cubic": np.array([[1, 0, -3, 2], [0, 1, -2, 1], [0, 0, 3, -2], [0, 0, -1, 1]]),
    "linear": np.array([[1, -1], [0, 1]]),
}


def _basis(kind: str, s: np.ndarray, order: int) -> np.ndarray:
    """(N, k) the bases' ``order``-th derivative with respect to s."""
    H = _HERMITE[kind]
    deg = H.shape[1] - 1
    out = np.zeros((len(s), H.shape[0]))
    for p in range(order, deg + 1):
        f = float(np.prod(np.arange(p - order + 1, p + 1)))
        out += f * np.outer(s ** (p - order), H[:, p])
    return out


def spline(kind: str, t, t_s, t_e, x0, v0, a0, x1, v1, a1, blend=None):
    """``(x, x_dot, x_ddot)`` (N, n) of CASPR's spline ``kind`` between the end states (n,), at the
    absolute times ``t`` of the segment's grid, which runs from ``t_s`` to ``t_e``."""
    x0, v0, a0, x1, v1, a1 = (np.atleast_1d(np.asarray(z, dtype=float)) for z in (x0, v0, a0, x1, v1, a1))
    t = np.asarray(t, dtype=float)
    if kind == "parabolic":
        return _parabolic(t, t_s, t_e, x0, x1, blend)
    T = t_e - t_s
    s = (t - t_s) / T
    c = {"quintic": [x0, T * v0, T**2 * a0, x1, T * v1, T**2 * a1], "cubic": [x0, T * v0, x1, T * v1],
         "linear": [x0, x1]}[kind]
    c = np.array(c)
    return _basis(kind, s, 0) @ c, _basis(kind, s, 1) @ c / T, _basis(kind, s, 2) @ c / T**2


def _parabolic(t, t_s, t_e, x_s, x_e, tb):
    """``Spline.ParabolicBlend``: constant acceleration for ``tb`` s at each end, a line between."""
    acc = (x_s - x_e) / (tb**2 - (t_e - t_s) * tb)
    x_b = x_s + acc * tb**2 / 2
    v_lin = ((x_s + x_e) / 2 - x_b) / ((t_e - t_s) / 2 - tb)
    t_b = t_s + tb
    n = len(t)
    x, xd, xdd = np.empty((n, len(x_s))), np.empty((n, len(x_s))), np.empty((n, len(x_s)))
    for i, ti in enumerate(t):
        if ti < t_b:
            x[i], xd[i], xdd[i] = x_s + acc * (ti - t_s) ** 2 / 2, acc * (ti - t_s), acc
        elif ti < t_e - tb:
            x[i], xd[i], xdd[i] = x_b + v_lin * (ti - t_b), v_lin, 0.0
        else:
            x[i], xd[i], xdd[i] = -acc * (ti - t_e) ** 2 / 2 + x_e, -acc * (ti - t_e), -acc
    return x, xd, xdd


_KIND = {"quintic_spline_trajectory": "quintic", "cubic_spline_trajectory": "cubic",
         "cubic_spline_average_velocity_trajectory": "cubic", "linear_spline_trajectory": "linear",
         "parabolic_blend_trajectory": "parabolic"}


# ------------------------------------------------------------------------------------ samples
@dataclass
class Samples:
    """A CASPR trajectory at CASPR's sample times.

    Attributes:
        t: (N,) s.
        q, qd, qdd: (N, n_q) CASPR's coordinates (NaN for the angles of rotation parts).
        rotations: ``{link index: (R (N, 3, 3), omega (N, 3), omega_dot (N, 3))}``: the relative
            rotation of each rotation part, its child-frame angular velocity and acceleration.
        notes: what the sampling remarked (segments that are not a whole number of steps).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    rotations: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)


class SamplingError(Exception):
    """A trajectory CASPR cannot sample either (the message says why)."""


def sample(bodies, traj: CasprTrajectory) -> Samples:
    """Sample ``traj`` (module docstring)."""
    if traj.samples is not None:
        return _from_file(bodies, traj)
    kind = _KIND[traj.type]
    parts_t, parts = [], []
    notes = []
    for p, a, b, grid, keep in _grids(traj, notes):
        blend = traj.blend[p] if traj.blend else None
        seg = _segment(bodies, kind, grid, a, b, blend)
        parts_t.append(grid[keep])
        parts.append(tuple(x[keep] for x in seg[:3]) + ({k: tuple(r[keep] for r in v) for k, v in seg[3].items()},))
    t = np.concatenate(parts_t)
    q, qd, qdd = (np.vstack([s[i] for s in parts]) for i in range(3))
    rotations = {k: tuple(np.concatenate([s[3][k][i] for s in parts]) for i in range(3)) for k in parts[0][3]}
    return Samples(t, q, qd, qdd, rotations, notes)


def _grids(traj, notes: list):
    """CASPR's sample times, segment by segment: ``(p, a, b, grid, keep)`` for the segment from point
    ``a`` to point ``b`` (``grid``: MATLAB's ``a.time:dt:b.time``; ``keep``: the samples it adds, its
    first one being the previous segment's last). The sample count is checked before any array is
    made; a segment that is not a whole number of time steps adds a note to ``notes``."""
    from ..limits import MAX_SAMPLES

    dt = traj.time_step
    span = traj.points[-1].time - traj.points[0].time
    if not (dt > 0 and span / dt <= MAX_SAMPLES):
        raise SamplingError(f"time_step = {dt:g} s over {span:g} s gives {span / dt:.3g} samples; at most "
                            f"{MAX_SAMPLES:,} per trajectory (docs/limits.md)")
    for p in range(len(traj.points) - 1):
        a, b = traj.points[p], traj.points[p + 1]
        grid = matlab_colon(a.time, dt, b.time)
        if len(grid) < 2:
            raise SamplingError(f"segment {p + 1} ({a.time:g} s to {b.time:g} s) is shorter than time_step = "
                                f"{dt:g} s: CASPR's spline through a single sample is undefined")
        if abs(grid[-1] - b.time) > 1e-9 * max(1.0, abs(b.time)):
            notes.append(f"segment {p + 1} lasts {b.time - a.time:g} s, not a whole number of time steps "
                         f"({dt:g} s): as in CASPR, its spline ends at its last sample, "
                         f"t = {grid[-1]:.9g} s, and the next segment starts at {b.time:g} s")
        yield p, a, b, grid, (slice(0, None) if p == 0 else slice(1, None))


def _segment(bodies, kind, grid, a, b, blend):
    n = bodies.n_q
    q, qd, qdd = (np.full((len(grid), n), np.nan) for _ in range(3))
    rotations = {}
    for i, (link, k) in enumerate(zip(bodies.links, bodies.offsets)):
        sc = [k + c for c in link.kind.scalar]
        if sc:
            x, xd, xdd = spline(kind, grid, grid[0], grid[-1], a.q[sc], a.q_dot[sc], a.q_ddot[sc], b.q[sc],
                                b.q_dot[sc], b.q_ddot[sc], blend)
            q[:, sc], qd[:, sc], qdd[:, sc] = x, xd, xdd
        if link.kind.rotation is not None:
            conv, first = link.kind.rotation
            s = slice(k + first, k + first + 3)
            Rs, Re = euler_rotation(conv, a.q[s]), euler_rotation(conv, b.q[s])
            phi = pin.log3(Rs.T @ Re)
            th_se = float(np.linalg.norm(phi))
            axis = phi / th_se if th_se > 0 else np.zeros(3)
            th, thd, thdd = (z[:, 0] for z in spline(kind, grid, grid[0], grid[-1], 0, 0, 0, th_se, 0, 0, blend))
            R = np.array([Rs @ pin.exp3(x * axis) for x in th])
            rotations[i] = (R, np.outer(thd, axis), np.outer(thdd, axis))
    return q, qd, qdd, rotations


def _from_file(bodies, traj) -> Samples:
    """A file trajectory: CASPR's q, q_dot, q_ddot as written; rotation parts as (R, omega, omega_dot)."""
    t, q, qd, qdd = traj.samples
    rotations = {}
    for i, (link, k) in enumerate(zip(bodies.links, bodies.offsets)):
        if link.kind.rotation is None:
            continue
        conv, first = link.kind.rotation
        s = slice(k + first, k + first + 3)
        R, w, wd = [], [], []
        for x, xd, xdd in zip(q[:, s], qd[:, s], qdd[:, s]):
            S, dS = euler_S(conv, x, xd)
            R.append(euler_rotation(conv, x))
            w.append(S @ xd)
            wd.append(S @ xdd + dS @ xd)
        rotations[i] = (np.array(R), np.array(w), np.array(wd))
        q, qd, qdd = q.copy(), qd.copy(), qdd.copy()
        q[:, s] = qd[:, s] = qdd[:, s] = np.nan
    return Samples(t, q, qd, qdd, rotations, [])


# ------------------------------------------------------------------------------ our coordinates
def to_ours(bodies, layout, s: Samples, nv: int):
    """``(x, v, a)`` (N, nv each): our coordinates and Pinocchio's velocity and acceleration.

    ``layout``: per CASPR link, the velocity indices of its physical joint in our model (chain order).
    """
    N = len(s.t)
    X, V, A = np.full((N, nv), np.nan), np.full((N, nv), np.nan), np.full((N, nv), np.nan)
    for i, (link, k, idx) in enumerate(zip(bodies.links, bodies.offsets, layout)):
        kind = link.kind
        if kind.sidecar == "free":
            R, w, wd = s.rotations[i]
            p, pd, pdd = s.q[:, k:k + 3], s.qd[:, k:k + 3], s.qdd[:, k:k + 3]
            vl = np.einsum("nji,nj->ni", R, pd)
            X[:, idx] = np.hstack([p, np.array([pin.log3(r) for r in R])])
            V[:, idx] = np.hstack([vl, w])
            A[:, idx] = np.hstack([np.einsum("nji,nj->ni", R, pdd) - np.cross(w, vl), wd])
            continue
        x, xd, xdd = s.q[:, k:k + kind.n_q], s.qd[:, k:k + kind.n_q], s.qdd[:, k:k + kind.n_q]
        if kind.rotation is not None:
            x, xd, xdd = _euler_rates(link, *s.rotations[i], s.t)
        for j, (_, _, _, c) in enumerate(kind.chain):
            X[:, idx[j]], V[:, idx[j]], A[:, idx[j]] = x[:, c], xd[:, c], xdd[:, c]
    return X, V, A


def _euler_rates(link, R, w, wd, t):
    conv = link.kind.rotation[0]
    ang = euler_angles(conv, R)
    rates, accs = np.empty_like(ang), np.empty_like(ang)
    for n, (x, wn, wdn) in enumerate(zip(ang, w, wd)):
        S = euler_S(conv, x)
        det = abs(float(np.linalg.det(S)))
        if det < SINGULAR_DET:
            raise SamplingError(f"at t = {t[n]:.9g} s joint {link.name!r} ({link.joint_type}) is "
                                f"{np.degrees(np.arccos(min(det, 1.0))):.4g} deg from the singularity of its "
                                f"Euler angles (|cos beta| = {det:.2e} < {SINGULAR_DET:g}): the angle rates are "
                                f"undefined there (CASPR falls back to finite differences)")
        rates[n] = np.linalg.solve(S, wn)
        _, dS = euler_S(conv, x, rates[n])
        accs[n] = np.linalg.solve(S, wdn - dS @ rates[n])
    return ang, rates, accs


def coordinates_from_caspr(bodies, layout, q_caspr, nv: int) -> np.ndarray:
    """Our coordinates (nv) of a CASPR configuration (free joints: position and rotation vector)."""
    q_caspr = np.asarray(q_caspr, dtype=float)
    x = np.full(nv, np.nan)
    for link, k, idx in zip(bodies.links, bodies.offsets, layout):
        kind = link.kind
        if kind.sidecar == "free":
            x[idx] = np.concatenate([q_caspr[k:k + 3], pin.log3(euler_rotation("xyz", q_caspr[k + 3:k + 6]))])
        else:
            for j, (_, _, _, c) in enumerate(kind.chain):
                x[idx[j]] = q_caspr[k + c]
    if not np.all(np.isfinite(x)):
        raise CasprError(bodies.path, "", "internal: a coordinate of the model was not mapped")
    return x


# -------------------------------------------------------------------------- operational space
def sample_operational(traj) -> Samples:
    """An operational-space trajectory (:class:`~mcdm_pin.caspr.trajectories.CasprOperationalTrajectory`)
    at CASPR's sample times: ``OperationalTrajectory.*Create`` samples every segment on the grid of
    :func:`sample` and splines every coordinate of ``y`` alone (``Spline.QuinticInterpolation`` or
    ``LinearInterpolation``, through the segment's grid); ``q``, ``qd``, ``qdd`` of the result hold
    ``y``, ``y_dot``, ``y_ddot``."""
    kind = _KIND[traj.type]
    ts, ys, notes = [], [], []
    for _, a, b, grid, keep in _grids(traj, notes):
        seg = spline(kind, grid, grid[0], grid[-1], a.q, a.q_dot, a.q_ddot, b.q, b.q_dot, b.q_ddot)
        ts.append(grid[keep])
        ys.append([x[keep] for x in seg])
    y, yd, ydd = (np.vstack([s[i] for s in ys]) for i in range(3))
    return Samples(np.concatenate(ts), y, yd, ydd, {}, notes)
