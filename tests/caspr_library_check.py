"""The CASPR library check, on a plain clone: every committed CASPR robot (``robots/caspr``) against the
reference values ``tests/data/caspr_reference.npz`` that ``tests/caspr_newton.py`` computed from
CASPR's XML (``python tools/caspr_library.py reference``), and case 1 solved by ProxQP and Clarabel.

Used by ``tests/test_caspr_library.py`` and by ``python tools/caspr_library.py table`` (which writes the
table of ``docs/caspr.md``).

**Comparison.** At each reference state the robot's state (q, v, a) is the committed trajectory's
sample at the same time (or, for states that are not on a trajectory, the state stored with the
reference). Compared, each to ``TOL`` relative to the largest entry of the reference quantity:

- every link frame's pose, velocity and classical acceleration (Pinocchio's forward kinematics of the
  committed URDF) with CASPR's (``caspr_newton.Model.kinematics``): the import of frames, joints and
  trajectories;
- the cable lengths;
- ``L``, ``M`` and ``tau = M qdd + h`` (``+ L_s^T f_s`` with passive springs) with CASPR's, through the map T between the two sets of
  velocities (``W_caspr T = J``, the links' twists): ``L = L_c T``, ``M = T^T M_c T``,
  ``tau = T^T tau_c``; and the actuation matrix, ``S = T^+ A_c`` up to the actuators' order;
- the interaction wrench maps ``u``, ``R^T`` of every joint with CASPR's, CASPR's force (parent
  frame) turned into the child frame.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin

REPO = Path(__file__).resolve().parents[1]
LIBRARY = REPO / "robots" / "caspr" / "library.json"
REFERENCE = REPO / "tests" / "data" / "caspr_reference.npz"
TOL = 1e-9  # relative: both sides are exact to rounding (1e-14 seen); 1e-9 is the bar
OBJ_TOL = 1e-6  # relative agreement of the case-1 objective, ProxQP vs Clarabel
# forces and motor torques vs Clarabel's own answer, relative to the largest of them (at least 1 N): case
# 1 is strictly convex, so its answer is unique, but Clarabel (an interior-point method) stops at a
# duality gap of 1e-11, which leaves it up to about sqrt(1e-11) = 3e-6 from a bound whose multiplier
# is zero. Measured: 1.2e-6 N at 2_DoF_VSD's rest with its `stiff` set (no force needed, f_min = 0: our
# answer is exactly 0, Clarabel's 1.2e-6 N), 1.6e-8 at worst on the 51 instants of every table state
X_TOL = 1e-5


def load_library() -> dict:
    return json.loads(LIBRARY.read_text(encoding="utf-8"))


def load_reference() -> dict:
    with np.load(REFERENCE, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}


def reference_states(ref: dict, model: str) -> list[dict]:
    """The reference states of one model: ``{name: array}`` each."""
    out = []
    s = 0
    while f"{model}:{s}:q_c" in ref:
        prefix = f"{model}:{s}:"
        out.append({k[len(prefix):]: v for k, v in ref.items() if k.startswith(prefix)})
        s += 1
    return out


def robot_of(entry):
    from mcdm_pin import Robot

    return Robot.load(REPO / entry["sidecar"])


def state_of(robot, entry, state, trajectory=None):
    """Our (q, v, a) at a reference state: the committed trajectory's sample at its time, or the state
    stored with the reference."""
    if "x" in state:
        return robot.configuration(state["x"]), state["v"], state["a"]
    t = float(state["t"])
    k = int(np.argmin(np.abs(trajectory.t - t)))
    if abs(trajectory.t[k] - t) > 1e-9:
        raise AssertionError(f"{entry['model']}: no sample of {trajectory.name!r} at t = {t}")
    return trajectory.q[k], trajectory.qd[k], trajectory.qdd[k]


def case1_states(robot, entry, ref: dict):
    """The states case 1 is solved at: the model's table trajectory, or (a model without a joint
    trajectory) the one instant at rest at ``q_initial`` stored with the reference."""
    from mcdm_pin import load_trajectory
    from mcdm_pin.trajectory import Trajectory

    if entry["table_trajectory"]:
        return load_trajectory(robot, entry["table_trajectory"])
    q, v, a = state_of(robot, entry, reference_states(ref, entry["model"])[0])
    return Trajectory("q_initial", np.zeros(1), q[None], v[None], a[None])


def _err(ours, ref) -> tuple[float, float]:
    """``(largest absolute difference, largest reference entry)``."""
    ours, ref = np.asarray(ours, dtype=float), np.asarray(ref, dtype=float)
    return float(np.abs(ours - ref).max(initial=0.0)), float(np.abs(ref).max(initial=0.0))


def worst(errors: list[dict]) -> dict:
    """Per quantity, over a model's states: the largest difference relative to the largest reference
    value of that quantity at any of them (a quantity that passes through zero at one state, a
    velocity at rest, is measured against its size elsewhere)."""
    out = {}
    for k in errors[0]:
        err = max(e[k][0] for e in errors)
        scale = max(e[k][1] for e in errors)
        out[k] = err / scale if scale > 0 else err
    return out


def compare(robot, links, state, q, v, a) -> dict:
    """``{quantity: (largest difference, largest reference entry)}`` at one reference state (module
    docstring); :func:`worst` turns a model's into relative errors."""
    from mcdm_pin import compute_terms

    model = robot.model
    data = model.createData()
    pin.forwardKinematics(model, data, q, v, a)
    pin.updateFramePlacements(model, data)
    pin.computeJointJacobians(model, data, q)
    poses, twists, accs, J = [], [], [], []
    for name in links:
        fid = model.getFrameId(name)
        M = data.oMf[fid]
        poses.append(np.concatenate([M.rotation.ravel(), M.translation]))
        twists.append(pin.getFrameVelocity(model, data, fid, pin.LOCAL).vector)
        accs.append(pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL).vector)
        J.append(pin.getFrameJacobian(model, data, fid, pin.LOCAL))
    J = np.vstack(J)
    ref_poses = np.concatenate([state["R"].reshape(-1, 9), state["P"]], axis=1)
    T = np.linalg.lstsq(state["W_c"], J, rcond=None)[0]
    terms = compute_terms(robot, q, v, a)
    tau_c = state["M_c"] @ state["qdd_c"] + state["h_c"]
    errors = {
        "pose": _err(np.array(poses), ref_poses),
        "velocity": _err(np.array(twists), state["vel"]),
        "acceleration": _err(np.array(accs), state["acc"]),
        "twist map": _err(state["W_c"] @ T, J),
        "lengths": _err(terms.lengths, state["lengths"]),
        "L": _err(terms.L, state["L_c"] @ T),
        "M": _err(terms.M, T.T @ state["M_c"] @ T),
        "tau": _err(terms.tau, T.T @ tau_c),
    }
    if state["A_c"].shape[1]:
        S = np.linalg.lstsq(T, state["A_c"], rcond=None)[0]
        errors["actuation"] = (_err(robot.actuation, S) if robot.n_act == S.shape[1] else (float("inf"), 1.0))
    u, RT = _interaction_child(state, links)
    errors["u"], errors["RT"] = _err(terms.u, u), _err(terms.RT, RT)
    return errors


def velocity_map(robot, links, state, q):
    """``T`` with ``W_caspr T = J`` (the links' twists, our velocity -> CASPR's), at our ``q``."""
    model = robot.model
    data = model.createData()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J = np.vstack([pin.getFrameJacobian(model, data, model.getFrameId(name), pin.LOCAL) for name in links])
    return np.linalg.lstsq(state["W_c"], J, rcond=None)[0]


def newton_residual(robot, links, state, q, f, tau_act) -> float:
    """Newton-Euler's residual of our answer ``(f, tau_act)`` at a reference state, relative: CASPR's
    ``M qdd + h`` (with the passive springs' ``L_s^T f_s``) and ``L`` from ``tests/caspr_newton.py``,
    brought to our coordinates by ``T^T``, against our actuation ``S tau_act``:
    ``|T^T (M_c qdd_c + h_c + L_c^T f) - S tau_act| / scale``."""
    T = velocity_map(robot, links, state, q)
    need = T.T @ (state["M_c"] @ state["qdd_c"] + state["h_c"])
    cab = T.T @ (state["L_c"].T @ f)
    act = robot.actuation @ np.asarray(tau_act, dtype=float).reshape(-1) if robot.n_act else np.zeros_like(need)
    scale = max(np.abs(need).max(initial=0.0), (np.abs(T.T @ state["L_c"].T) @ np.abs(f)).max(initial=0.0),
                np.abs(act).max(initial=0.0), 1e-300)
    return float(np.abs(need + cab - act).max(initial=0.0) / scale)


def _interaction_child(state, links):
    """CASPR's interaction maps with the force turned from the parent frame into the child frame."""
    p = len(links)
    R = state["R"]
    parents = state["parent"]
    u = state["a_c"].reshape(p, 6).copy()
    RT = state["RT_c"].reshape(p, 6, -1).copy()
    for k in range(p):
        Rp = np.eye(3) if parents[k] == 0 else R[parents[k] - 1]
        Rpe = Rp.T @ R[k]
        u[k, :3] = Rpe.T @ u[k, :3]
        RT[k, :3] = Rpe.T @ RT[k, :3]
    return u, RT


def solve_case1(robot, traj, instants=None):
    """Case 1 along ``traj`` (every sample, or ``instants`` of them spread evenly) with ProxQP and
    Clarabel: ``(ProxQP run, Clarabel run on the same instants)``."""
    from mcdm_pin import InverseDynamics

    sub = traj if instants is None else traj.subsample(instants)
    prox = InverseDynamics.for_case(robot, 1).solve_trajectory(sub, progress=False)
    clar = InverseDynamics.for_case(robot, 1, solver="clarabel").solve_trajectory(sub, progress=False)
    return prox, clar


def objective_agreement(prox, clar) -> tuple[int, float]:
    """``(instants where both found an optimum, largest objective difference there relative to the
    objective, or to 1 N^2 when the objective is smaller)``; an instant where one back-end found an
    optimum and the other did not is a disagreement (inf)."""
    if np.any(prox.found != clar.found):
        return int((prox.found & clar.found).sum()), float("inf")
    both = prox.found & clar.found
    if not both.any():
        return 0, 0.0
    o1, o2 = prox.objective[both], clar.objective[both]
    return int(both.sum()), float(np.max(np.abs(o1 - o2) / np.maximum(np.abs(o2), 1.0)))


def clarabel_alone(robot, traj) -> dict:
    """Case 1 at every instant of ``traj``, by the default chain and by Clarabel alone on the same
    problem (:func:`~mcdm_pin.solvers.clarabel_.clarabel_solve`: no scaling, polish or least-norm
    stage, so nothing of the chain's is shared but the problem's assembly). Returns ``instants``
    compared (a state the model refuses, a zero-length cable, is counted in ``refused``), ``optimal``
    (both found the optimum), ``mismatch`` (the times where one found an optimum and the other did
    not), and the largest relative differences of the ``objective`` and of the unknowns ``x`` (forces,
    then motor torques) where both did."""
    from mcdm_pin import InverseDynamics
    from mcdm_pin.exceptions import StateError
    from mcdm_pin.problem import Context
    from mcdm_pin.solvers import OPTIMAL
    from mcdm_pin.solvers.clarabel_ import clarabel_solve

    ours_id = InverseDynamics.for_case(robot, 1, diagnose=False)
    out = dict(instants=0, refused=0, optimal=0, mismatch=[], objective=0.0, x=0.0)
    for k in range(len(traj)):
        try:
            terms = ours_id.evaluate(traj.q[k], traj.qd[k], traj.qdd[k])
        except StateError:
            out["refused"] += 1
            continue
        ours = ours_id.solve(traj.q[k], traj.qd[k], traj.qdd[k])
        raw = clarabel_solve(ours_id.problem.assemble(terms, Context(robot, None)))
        out["instants"] += 1
        if ours.found != (raw.status == OPTIMAL):
            out["mismatch"].append(float(traj.t[k]))
        if not (ours.found and raw.status == OPTIMAL):
            continue
        out["optimal"] += 1
        x = np.concatenate([ours.f, np.atleast_1d(ours.tau_act) if ours.tau_act is not None else []])
        out["objective"] = max(out["objective"], abs(ours.objective - raw.objective) / max(abs(raw.objective), 1.0))
        out["x"] = max(out["x"], float(np.abs(x - raw.x).max() / max(np.abs(raw.x).max(), 1.0)))
    return out


def agrees(alone: dict) -> bool:
    """Clarabel alone and the default chain agree: the same instants have an optimum, and there the
    objectives agree to ``OBJ_TOL`` and the unknowns to ``X_TOL``."""
    return not alone["mismatch"] and alone["objective"] <= OBJ_TOL and alone["x"] <= X_TOL


# ------------------------------------------------------------------ reference values from the XML
def reference_state(model, q, qd, qdd, **extra) -> dict:
    """What :func:`compare` needs at one CASPR state, computed by ``tests/caspr_newton.py``."""
    R, P, w, wd, v, a = model.kinematics(q, qd, qdd)
    p = len(model.links)
    M, h = model.terms(q, qd, qdd)
    h = h + model.spring_generalized(q)  # the passive springs' known tensions join C + G (CASPR's b)
    a_c, RT_c = model.interaction_map(q, qd, qdd)
    out = dict(q_c=q, qd_c=qd, qdd_c=qdd, R=np.array(R[1:]), P=np.array(P[1:]),
               vel=np.array([np.concatenate([R[k].T @ v[k], R[k].T @ w[k]]) for k in range(1, p + 1)]),
               acc=np.array([np.concatenate([R[k].T @ a[k], R[k].T @ wd[k]]) for k in range(1, p + 1)]),
               lengths=model.lengths(q), L_c=model.cable_jacobian(q), M_c=M, h_c=h, W_c=model.twist_jacobian(q),
               A_c=model.actuation(), a_c=a_c, RT_c=RT_c, parent=np.array([link.parent for link in model.links]))
    out.update({k: np.asarray(val) for k, val in extra.items()})
    return out


def ours_from_caspr(bodies_xml, robot, q, qd, qdd):
    """Our coordinates, velocity and acceleration of a CASPR state, by the importer's conversion (what
    :func:`compare` then checks against CASPR's kinematics)."""
    from mcdm_pin.caspr import CasprTrajectory, read_bodies, sample, to_ours

    bodies = read_bodies(bodies_xml)
    layout = [robot.joint(link.ident).idx_v for link in bodies.links]
    tr = CasprTrajectory(id="state", type="file_trajectory", time_step=1.0, points=(), element="",
                         samples=(np.zeros(1), np.asarray(q)[None], np.asarray(qd)[None], np.asarray(qdd)[None]))
    X, V, A = to_ours(bodies, layout, sample(bodies, tr), robot.nv)
    return X[0], V[0], A[0]
