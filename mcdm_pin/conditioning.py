r"""Conditioning diagnostics: Euler-angle singularities and wrench closure.

**Euler angles.** A spherical joint's coordinates are xyz Euler angles; the map from their rates to
the child's angular velocity, :math:`\omega = S(q)\dot q`, has :math:`|\det S| = |\cos q_2|`, singular
at :math:`q_2 = \pm 90` deg (gimbal lock). The inverse dynamics *in coordinates* stays defined there,
but Euler rates derived from a motion (a trajectory's :math:`\dot q = S^{-1}\omega`) are amplified by
:math:`1/|\cos q_2|`, and so are their rounding errors: :func:`~mcdm_pin.trajectory.quintic_trajectory`
refuses poses with :math:`|\det S| <` :data:`~mcdm_pin.trajectory.SINGULAR_DET` and names the joint,
the instant and the angles. :func:`euler_singularity` reports the margin of any state.

**Wrench closure.** Cables only pull. They can produce *every* generalised force (given large enough
forces) at a configuration iff :math:`L` has rank :math:`n_v` and some strictly positive force vector
is in the null space of :math:`L^T` (:math:`L^T f = 0,\ f > 0`). Otherwise, by Gordan's theorem there
is a motion direction :math:`y` with :math:`L y \ge 0`, :math:`L y \ne 0` or :math:`L y = 0`: no
cable shortens along :math:`y`, so no cable can pull the robot that way. :func:`wrench_closure` finds
such a direction by linear programming (HiGHS) and names the coordinates it moves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def euler_singularity(robot, q) -> dict[str, float]:
    """``{spherical joint given by angles: |det S(q)|}`` (``|cos q2|`` for xyz Euler angles; 0 = gimbal
    lock) at coordinates ``q`` (nv). Native ball joints (quaternions) have no singularity and are left
    out."""
    from .trajectory import SphericalKinematics

    q = robot.check_vector(q, "q")
    out = {}
    for joint in robot.joints:
        if joint.type == "spherical" and joint.parametrization != "quaternion":
            out[joint.name] = abs(float(np.linalg.det(SphericalKinematics(robot, joint).S(q[joint.idx_v]))))
    return out


@dataclass
class Closure:
    """Wrench closure at one configuration.

    Attributes:
        rank: rank of ``L`` (tolerance 1e-9 relative).
        closed: the cables can produce every generalised force.
        direction: (nv,) a motion direction no cable can pull along (``None`` if closed).
        message: one sentence for reports and error messages.
    """

    rank: int
    closed: bool
    direction: np.ndarray | None
    message: str


def wrench_closure(robot, q, L: np.ndarray | None = None) -> Closure:
    """Can the cables pull the robot every way at ``q``? (module docstring)"""
    from scipy.optimize import linprog

    if L is None:
        from .model.terms import compute_terms

        L = compute_terms(robot, q).L
    m, nv = L.shape
    scale = max(np.abs(L).max(initial=0.0), 1e-300)
    Ls = L / scale
    rank = int(np.linalg.matrix_rank(Ls, tol=1e-9))
    pos = linprog(np.zeros(m), A_eq=Ls.T, b_eq=np.zeros(nv), bounds=[(1.0, None)] * m, method="highs")
    if rank == nv and pos.status == 0:
        return Closure(rank, True, None, f"cables can pull every one of the {nv} DoF both ways "
                                         f"(rank L = {nv}, a strictly positive f with L^T f = 0 exists)")
    if rank < nv:
        y = np.linalg.svd(Ls)[2][-1]  # L y = 0: cables neither pull nor resist along y
        why = f"cables span only {rank} of {nv} DoF (rank L = {rank}): no cable acts along"
    else:
        # maximise sum(L y) with L y >= 0, |y| <= 1: a direction along which no cable shortens
        res = linprog(-Ls.sum(axis=0), A_ub=-Ls, b_ub=np.zeros(m), bounds=[(-1.0, 1.0)] * nv,
                      method="highs")
        y = res.x if res.status == 0 else np.linalg.svd(Ls)[2][-1]
        why = "no cable shortens (so none can pull the robot) along"
    y = y / np.abs(y).max()
    if y[np.argmax(np.abs(y))] < 0:
        y = -y
    top = np.argsort(-np.abs(y))[:3]
    # L's columns: the coordinates, or with couplings the independent ones
    couplings = getattr(robot, "couplings", None)
    column = np.arange(robot.nv) if couplings is None or len(y) == robot.nv else couplings.independent
    names = ", ".join(f"{y[i]:+.2g} {robot.coordinate_names[column[i]]}" for i in top if abs(y[i]) > 1e-6)
    joints = sorted({j.name for j in robot.joints for i in top if abs(y[i]) > 1e-6 and column[i] in j.idx_v})
    return Closure(rank, False, y, f"wrench closure lost: {why} the motion direction ({names}) of joint(s) "
                                   f"{', '.join(joints)}; add or re-route cables there")
