r"""RMR's problem on the thoracoscapular shoulder model (Belli et al., PLOS ONE 2023), per frame.

RMR (the Rapid Muscle Redundancy solver) minimises, at each frame,

.. math:: \sum_i a_i^2 + \sum_j w_j c_j^2

over the 33 muscles' activations :math:`a_i \in [0, 1]` (muscle force ``passive + gain a`` with
RMR's force model: OpenSim's ``a F_0 f_L f_V cos(alpha) + F_0 f_P cos(alpha)`` with a rigid tendon,
*without* the fibre damping's ``F_0 beta v cos(alpha)`` that OpenSim's Millard muscle adds; the curves
stay those of OpenSim's damped model, as RMR reads them from it) and the 17 ``CoordinateActuator``
controls :math:`c_j` (torque ``F_opt c``; ``w`` = 0 on the thorax's six coordinates, the elbow and the
forearm, 10 on the shoulder girdle's and glenohumeral coordinates), subject to the equation of motion
and, "with GH", the glenohumeral reaction force within the glenoid cone
(:mod:`mcdm_pin.osim.glenoid`). The robot of ``robots/opensim/tsm_rmr.yaml`` declares the weights and
the cone; :func:`rmr_robot` sets RMR's activation bounds ``[0, 1]`` (RMR overrides the muscles' force,
so the model's ``minimum_activation`` 0.01 does not bound it) and drops the damping. RMR's states are
its filtered IK (:func:`rmr_kinematics`, :func:`rmr_states`). RMR's answers (``xsol``: 33
activations, then the 17 controls in the model's actuator order, then a 51st column that RMR's
``Results/RMR analysis/average_serratus_anterior.m`` appended afterwards: the mean of the three
serratus anterior activations, columns 5-7) are compared with ours by :func:`rmr_objective` and
:func:`rmr_in_our_problem`.

In a shrug RMR frees the accelerations of ``plane_elv`` and ``axial_rot`` (poorly defined with the arm
hanging); here their actuators then weigh 0 (free torques at the measured accelerations).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..constraints import InteractionCone
from ..model.cables import CableSet
from ..model.muscles_osim import OpenSimMuscles
from ..objectives import MinActivations
from ..problem import Problem
from ..solvers.base import cone_violation_deg
from .actuators import CONTROL_CAP
from .document import read_osim
from .motion import Table, motion_states, read_table

REPO = Path(__file__).resolve().parents[2]
SIDECAR = REPO / "robots" / "opensim" / "tsm_rmr.yaml"
RATE = 100.0  # Hz: RMR's frames, frame k at k / RATE s
N_MUSCLES, N_ACTUATORS = 33, 17
SHRUG_FREE = ("plane_elv_actuator", "axial_rot_actuator")
SHRUG_FREED = ("plane_elv", "axial_rot")  # the coordinates whose accelerations RMR leaves free in a shrug
GH = "GlenoHumeral"


def rmr_robot(motion: str = "abd01", sidecar=None) -> Robot:
    """The TSM as RMR poses it (``sidecar``: default the repository's ``robots/opensim/tsm_rmr.yaml``):
    activations in [0, 1] (RMR's bounds: it overrides the muscles' force, so the model's
    ``minimum_activation`` 0.01 does not apply); no fibre damping in the passive force (RMR's
    ``PMuscForce``); for a shrug, plane_elv's and axial_rot's actuators weigh 0."""
    from ..robot import Robot

    robot = Robot.load(SIDECAR if sidecar is None else sidecar)
    cables = robot.cables
    muscles = OpenSimMuscles([dataclasses.replace(m, a_min=0.0, damping=0.0) for m in cables.muscles.muscles])
    cables = CableSet(robot.model, cables.cables, muscles=muscles, muscle_cables=muscles.names)
    acts = robot.actuators
    if motion.startswith("shrug"):
        acts = tuple(dataclasses.replace(a, weight=0.0) if a.label in SHRUG_FREE else a for a in acts)
    return Robot(robot.model, cables, robot.joints, acts, robot.name, sidecar=robot.sidecar,
                 couplings=robot.couplings, coordinate_names=robot.coordinate_names, source=robot.source,
                 notes=robot.notes)


def frame_rows(files, every: int = 1) -> np.ndarray:
    """RMR's frame indices (``k / RATE`` s) inside the motion's time span, every ``every``-th."""
    t = read_table(files[0]).time
    k = np.arange(int(np.ceil(t[0] * RATE - 1e-9)), int(np.floor(t[-1] * RATE + 1e-9)) + 1)
    return k[::every]


def frame_states(robot, files, rows):
    """``(q, v, a)`` at RMR's frames ``rows`` (frame k at ``k / RATE`` s) from the motion's coordinate,
    speed and acceleration tables ``files`` (:func:`~mcdm_pin.osim.motion.motion_states`)."""
    return motion_states(robot.source, read_osim(robot.source.maps.source), *files, np.asarray(rows) / RATE)


IK_FOLDER = REPO / "robots" / "opensim" / "motions" / "ik"  # RMR's IK solutions (Results/IK solutions)
LOWPASS_HZ = 3.0  # RMR's filter of the IK coordinates (loadFilterCropArray.m)


def rmr_kinematics(ik_file) -> tuple:
    """RMR's states, as ``RMR_analysis.m`` makes them from an IK solution (``.mot``): every coordinate
    low-passed by a 4th-order Butterworth filter at 3 Hz run forwards and backwards (MATLAB's
    ``filtfilt``: odd extension of ``3 (5 - 1)`` samples), then differentiated twice by MATLAB's
    ``gradient`` (central differences, one-sided at the ends). Three :class:`Table` (coordinates,
    speeds, accelerations) on the IK's time grid, row ``k`` at ``k / 100`` s (RMR's frame ``k``)."""
    from scipy.signal import butter, filtfilt

    ik = read_table(ik_file)
    dt = float(ik.time[1] - ik.time[0])
    b, a = butter(4, LOWPASS_HZ / (0.5 / dt), "low")
    q = filtfilt(b, a, ik.data, axis=0, padtype="odd", padlen=3 * (max(len(a), len(b)) - 1))
    u = np.gradient(q, dt, axis=0)
    return tuple(Table(ik.labels, ik.time, x, ik.in_degrees) for x in (q, u, np.gradient(u, dt, axis=0)))


def rmr_states(robot, motion: str, rows=None, folder=None):
    """``(q, v, a)`` at RMR's frames ``rows`` (default: all) of a motion, from RMR's filtered IK
    (:func:`rmr_kinematics` of ``<folder>/<MOTION>.mot``, default the committed copies)."""
    tables = rmr_kinematics(Path(folder or IK_FOLDER) / f"{motion.upper()}.mot")
    rows = np.arange(len(tables[0].time)) if rows is None else np.asarray(rows)
    return motion_states(robot.source, read_osim(robot.source.maps.source), *tables, tables[0].time[rows])


def excerpt_answers(folder, cone: bool):
    """``(rows, xsol)`` of RMR's answers kept beside a committed motion excerpt (``rmr_xsol_*.csv``)."""
    data = np.loadtxt(Path(folder) / f"rmr_xsol_{'with' if cone else 'without'}_GH.csv", delimiter=",", ndmin=2)
    return data[:, 0].astype(int), data[:, 1:]


def rmr_problem(robot, cone: bool) -> Problem:
    """RMR's objective (activations, the actuators' ``w c^2`` added by the problem), and the cone."""
    return Problem(robot, MinActivations(), [InteractionCone(GH)] if cone else [])


def actuator_weights(robot) -> tuple:
    """``(F_opt, w)`` per actuator: the torque is ``F_opt c``, the objective's term ``w c^2``."""
    f_opt = np.array([float(a.tau_max[0]) for a in robot.actuators]) / CONTROL_CAP
    return f_opt, np.array([a.weight for a in robot.actuators]) * f_opt ** 2


def rmr_objective(robot, xrow) -> float:
    """RMR's objective at its answer: ``sum a^2 + sum w c^2`` (our weights, RMR's values)."""
    _, w = actuator_weights(robot)
    x = np.asarray(xrow, dtype=float)
    return float(np.sum(x[:N_MUSCLES] ** 2) + np.sum(w * x[N_MUSCLES:N_MUSCLES + N_ACTUATORS] ** 2))


def rmr_in_our_problem(ident, terms, qp, xrow, freed=()) -> dict:
    """RMR's answer as our unknowns ``[f; tau]`` at our state and how far it is from our constraints:
    the equation of motion's residual (largest generalized force, N m or N, and relative; ``eom_raw``
    with RMR's own controls of the weightless actuators, ``eom_abs`` with those refitted to our state
    by least squares, which changes no objective: the thorax's, the forearm's, in a shrug also
    plane_elv's and axial_rot's actuators are free in both problems), the activation bounds, the cone
    (degrees beyond it). ``closed_*``: the point of our feasible set nearest RMR's answer
    (:func:`close_answer`; ``closed_change`` the distance), with its objective ``closed_objective``
    and its constraints checked as RMR's answer's are. ``eom_freed``: ``eom_raw`` with the accelerations
    of the coordinates ``freed`` left free (least squares), as RMR leaves plane_elv's and axial_rot's in
    a shrug."""
    robot = ident.robot
    x = np.asarray(xrow, dtype=float)[:N_MUSCLES + N_ACTUATORS]
    y = _unknowns(robot, terms.muscles, x)
    n = terms.tau.shape[0]
    r = qp.A[:n] @ y - qp.b[:n]
    raw = float(np.abs(r).max())
    if freed:  # the residual moves by basis^T M e_j per unit acceleration of a freed coordinate j
        maps = robot.source.maps
        cols = terms.basis.T @ terms.M[:, [int(maps.coordinate_v[maps.coordinates.index(c)]) for c in freed]]
        r = r - cols @ np.linalg.lstsq(cols, r, rcond=None)[0]
    free = robot.m + np.flatnonzero(np.array([a.weight for a in robot.actuators]) == 0.0)
    y[free] -= np.linalg.lstsq(qp.A[:n, free], qp.A[:n] @ y - qp.b[:n], rcond=None)[0]
    out = dict(_check(robot, terms, qp, y, x), eom_raw=raw, eom_freed=float(np.abs(r).max()))
    z = close_answer(robot, terms, qp, x)
    closed = _check(robot, terms, qp, _unknowns(robot, terms.muscles, z), z)
    out.update({f"closed_{k}": v for k, v in closed.items()}, closed_change=float(np.linalg.norm(z - x)),
               closed_objective=rmr_objective(robot, z))
    return out


RMR_W = np.r_[np.zeros(8), np.full(9, 10.0)]  # RMR's w on its controls (the model's actuator order)


def close_answer(robot, terms, qp, x, freed=()) -> np.ndarray:
    """The point of our problem's feasible set nearest RMR's answer ``x`` (33 activations, 17 controls;
    Euclidean distance in these units): our equation of motion exactly (with the accelerations of the
    coordinates ``freed`` left free, as RMR's shrug), activations in their bounds, and our cones
    (:func:`rmr_socp`). Our optimum of the same problem is never above its objective."""
    return rmr_socp(robot, terms, qp, x, freed)


def rmr_exact_objective(x) -> float:
    """RMR's own objective ``sum a^2 + sum w c^2`` with RMR's ``w`` (:data:`RMR_W`: 10 also on
    plane_elv's and axial_rot's controls in a shrug, where ours weigh 0)."""
    x = np.asarray(x, dtype=float)
    return float(np.sum(x[:N_MUSCLES] ** 2) + np.sum(RMR_W * x[N_MUSCLES:N_MUSCLES + N_ACTUATORS] ** 2))


def rmr_socp(robot, terms, qp, target=None, freed=()) -> np.ndarray:
    """A second-order-cone program over RMR's unknowns ``z`` (33 activations, 17 controls) on our
    problem's constraints at this state (Clarabel): our equation of motion (projected off the
    directions ``basis^T M e_j`` of the ``freed`` coordinates' accelerations, which are then free),
    the activation bounds and the cones. Minimises ``|z - target|^2``, or without ``target`` RMR's
    own objective (:func:`rmr_exact_objective`): RMR's exact problem, with ``freed`` its shrug's."""
    import clarabel
    from scipy import sparse

    n, k = terms.tau.shape[0], robot.cables.muscle_index
    f_opt, _ = actuator_weights(robot)
    nz = N_MUSCLES + N_ACTUATORS
    D = np.zeros((qp.A.shape[1], nz))  # y = y0 + D z
    D[k, np.arange(N_MUSCLES)] = terms.muscles.gain
    D[robot.m + np.arange(N_ACTUATORS), N_MUSCLES + np.arange(N_ACTUATORS)] = f_opt
    y0 = _unknowns(robot, terms.muscles, np.zeros(nz))
    E, e = qp.A[:n] @ D, qp.b[:n] - qp.A[:n] @ y0
    if freed:
        maps = robot.source.maps
        C = terms.basis.T @ terms.M[:, [int(maps.coordinate_v[maps.coordinates.index(c)]) for c in freed]]
        Q = np.linalg.svd(C)[0][:, len(freed):]  # the equation's directions the freed accelerations miss
        E, e = Q.T @ E, Q.T @ e
    eye = np.eye(nz)[:N_MUSCLES]
    rows, rhs = [E, -eye, eye], [e, -terms.muscles.a_min, terms.muscles.a_max]
    cones = [clarabel.ZeroConeT(E.shape[0]), clarabel.NonnegativeConeT(2 * N_MUSCLES)]
    for c in qp.cones:  # (tan(angle) axis.F, basis F) in the second-order cone, F = g + G y
        T = np.vstack([np.tan(np.radians(c.angle_deg)) * c.axis, c.basis])
        rows.append(-T @ c.G @ D)
        rhs.append(T @ (c.g + c.G @ y0))
        cones.append(clarabel.SecondOrderConeT(3))
    if target is None:
        P, q = 2.0 * np.diag(np.r_[np.ones(N_MUSCLES), RMR_W]), np.zeros(nz)
    else:
        P, q = 2.0 * np.eye(nz), -2.0 * np.asarray(target, dtype=float)[:nz]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    sol = clarabel.DefaultSolver(sparse.csc_matrix(P), q, sparse.csc_matrix(np.vstack(rows)),
                                 np.concatenate(rhs), cones, settings).solve()
    return np.array(sol.x) if str(sol.status) in ("Solved", "AlmostSolved") else np.full(nz, np.nan)


def _unknowns(robot, st, x) -> np.ndarray:
    """Our unknowns ``[f; tau]`` of RMR's ``x``: ``f = passive + gain a``, ``tau = F_opt c``."""
    f = np.zeros(robot.m)
    f[robot.cables.muscle_index] = st.passive + st.gain * x[:N_MUSCLES]
    f_opt, _ = actuator_weights(robot)
    return np.concatenate([f, f_opt * x[N_MUSCLES:N_MUSCLES + N_ACTUATORS]])


def _check(robot, terms, qp, y, x) -> dict:
    n = terms.tau.shape[0]
    r = qp.A[:n] @ y - qp.b[:n]
    scale = max(np.abs(terms.tau).max(), 1e-300)
    cone = float(cone_violation_deg(qp, y).max(initial=0.0)) if qp.cones else 0.0
    st, a = terms.muscles, x[:N_MUSCLES]
    return dict(eom_abs=float(np.abs(r).max()), eom_rel=float(np.abs(r).max() / scale),
                bounds=float(max((st.a_min - a).max(), (a - st.a_max).max(), 0.0)), cone_deg=cone,
                angle_deg=float(np.degrees(np.arccos(np.clip(
                    _cos(terms.wrenches(y)[robot.joint_names.index(GH), :3], robot, terms), -1, 1)))))


def _cos(F_child, robot, terms) -> float:
    j = robot.joint_names.index(GH)
    F = terms.R_socket[j] @ F_child
    return float(F @ terms.socket_axes[j] / max(np.linalg.norm(F), 1e-300))
