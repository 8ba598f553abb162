"""CASPR's whole model library, on a plain clone: every committed conversion (``robots/caspr``) against
``tests/caspr_newton.py``'s independent Newton-Euler reference (``tests/data/caspr_reference.npz``,
computed from CASPR's XML by ``python tools/caspr_library.py reference``; the comparison is described
in ``tests/caspr_library_check.py``) to 1e-9 relative, and case 1 along each model's table trajectory
solved by the default chain and by Clarabel, objectives to 1e-6 relative (the issue's bars), and by
Clarabel alone (no stage of the chain shared), forces to 1e-5 relative (X_TOL)."""

from __future__ import annotations

import pytest

from mcdm_pin import load_trajectory

from .caspr_library_check import (OBJ_TOL, REPO, TOL, X_TOL, agrees, case1_states, clarabel_alone, compare,
                                  load_library, load_reference, newton_residual, objective_agreement,
                                  reference_states, robot_of, solve_case1, state_of, worst)

LIBRARY = load_library()
IMPORTED = [m for m in LIBRARY["models"] if m["status"] == "imported"]
REFUSED = [m for m in LIBRARY["models"] if m["status"] != "imported"]
INSTANTS = 7  # spread over each table trajectory: both back-ends, every model (the table uses 51)


@pytest.fixture(scope="module")
def reference():
    return load_reference()


def test_library_is_the_whole_of_caspr():
    """36 models of CASPR's library (``data/model_config/models``) plus the paper's SR arm; every
    refusal names the element and the reason."""
    names = [m["model"] for m in LIBRARY["models"]]
    assert len(names) == len(set(names)) and len([n for n in names if n != "SR_model"]) == 36
    for m in REFUSED:
        why = " ".join(str(v) for v in m.get("cable_sets", {}).values()) + " ".join(m.get("notes", []))
        assert "refused" in why or m.get("reason"), m["model"]


@pytest.mark.parametrize("entry", IMPORTED, ids=[m["model"] for m in IMPORTED])
def test_terms_match_the_newton_reference(entry, reference):
    robot = robot_of(entry)
    tid = entry["table_trajectory"]
    traj = load_trajectory(robot, tid) if tid else None
    states = reference_states(reference, entry["model"])
    assert states, f"no reference state for {entry['model']}"
    errors = [compare(robot, entry["links"], st, *state_of(robot, entry, st, traj)) for st in states]
    w = worst(errors)
    bad = {k: v for k, v in w.items() if not v <= TOL}
    assert not bad, bad


@pytest.mark.parametrize("entry", IMPORTED, ids=[m["model"] for m in IMPORTED])
def test_case1_answers_meet_the_newton_reference(entry, reference):
    """Case 1's answers (cable forces, unbounded motors' torques) at the reference states meet CASPR's
    equation of motion as ``tests/caspr_newton.py`` writes it (passive springs' known tensions on the
    right-hand side) to 1e-9 relative; at least one state of every model that solves case 1 somewhere."""
    from mcdm_pin import InverseDynamics

    robot = robot_of(entry)
    tid = entry["table_trajectory"]
    traj = load_trajectory(robot, tid) if tid else None
    solver = InverseDynamics.for_case(robot, 1, diagnose=False)
    residuals = []
    for st in reference_states(reference, entry["model"]):
        q, v, a = state_of(robot, entry, st, traj)
        try:
            r = solver.solve(q, v, a)
        except Exception as exc:  # a state the model refuses (a zero-length cable)
            assert "zero length" in str(exc), exc
            continue
        if r.found:
            residuals.append(newton_residual(robot, entry["links"], st, q, r.f, r.tau_act))
    assert all(x <= TOL for x in residuals), (entry["model"], residuals)


@pytest.mark.parametrize("entry", [m for m in IMPORTED if m["table_trajectory"]],
                         ids=[m["model"] for m in IMPORTED if m["table_trajectory"]])
def test_case1_along_its_own_trajectory_agrees_with_clarabel(entry):
    """Both back-ends give the same status at every instant and, where optimal, the same objective.
    A model whose cables cannot hold it along its own trajectory (BioBiped_one_leg, RoboyUpperBody:
    infeasible at every instant, for both) is reported so in docs/caspr.md; an instant where a cable
    has zero length (Example_point_XZ's point mass reaching an anchor) has no direction to pull in and
    is refused by the model, not by a solver."""
    from mcdm_pin.exceptions import StateError

    robot = robot_of(entry)
    traj = load_trajectory(robot, entry["table_trajectory"]).subsample(INSTANTS)
    keep = []
    for k in range(len(traj)):
        try:
            robot.check_configuration(traj.q[k])
            from mcdm_pin import compute_terms

            compute_terms(robot, traj.q[k], traj.qd[k], traj.qdd[k])
            keep.append(k)
        except StateError as exc:
            assert "zero length" in str(exc), exc
    assert keep, entry["model"]
    from mcdm_pin.trajectory import Trajectory

    sub = Trajectory(traj.name, traj.t[keep], traj.q[keep], traj.qd[keep], traj.qdd[keep])
    prox, clar = solve_case1(robot, sub)
    assert list(prox.status) == list(clar.status), (entry["model"], prox.status, clar.status)
    n, diff = objective_agreement(prox, clar)
    assert diff <= OBJ_TOL, (entry["model"], diff)


@pytest.mark.parametrize("entry", IMPORTED, ids=[m["model"] for m in IMPORTED])
def test_case1_agrees_with_clarabel_alone(entry, reference):
    """Clarabel alone on the same problem (no scaling, polish or least-norm stage of the chain), along
    the model's table trajectory or at rest: an optimum at the same instants, objectives to 1e-6 and
    forces (motor torques) to 1e-5 relative."""
    robot = robot_of(entry)
    alone = clarabel_alone(robot, case1_states(robot, entry, reference).subsample(INSTANTS))
    assert alone["instants"] > 0, entry["model"]
    assert not alone["mismatch"], (entry["model"], "one found an optimum, the other not, at t =", alone["mismatch"])
    assert alone["objective"] <= OBJ_TOL and alone["x"] <= X_TOL, (entry["model"], alone)


def test_carex_singular_mass_matrix_is_a_warning_of_info(capsys):
    """CAREX's links have no inertia about their own axes: ``info`` warns that the mass matrix is
    singular and exits 0 (inverse dynamics never inverts it)."""
    import numpy as np

    from mcdm_pin import compute_terms
    from mcdm_pin.cli import main

    entry = next(m for m in IMPORTED if m["model"] == "CAREX")
    robot = robot_of(entry)
    M = compute_terms(robot, np.zeros(robot.nq), np.zeros(robot.nv), np.zeros(robot.nv)).M
    assert np.linalg.eigvalsh(M).min() < 1e-12 * np.abs(M).max()
    assert main(["info", str(REPO / entry["sidecar"])]) == 0
    out = capsys.readouterr()
    assert "[warn] mass matrix singular" in out.out + out.err


def test_planar_snake_arm_first_instants_are_solved():
    """PlanarSnakeArm's ``test_short`` at t = 0.005-0.075 s (15 samples), the arm held straight: the
    scaling (Ruiz equilibration of a cable column 2e-7..6e-4 of the motors') spread the scaled Hessian
    over 14 decades and every back-end answered 'inaccurate'; the scaled solver now retries the problem
    as given when the scaled answer fails its check, and every instant is Clarabel's optimum."""
    entry = next(m for m in IMPORTED if m["model"] == "PlanarSnakeArm")
    robot = robot_of(entry)
    traj = load_trajectory(robot, entry["table_trajectory"])
    from mcdm_pin.trajectory import Trajectory

    first = slice(1, 16)
    sub = Trajectory(traj.name, traj.t[first], traj.q[first], traj.qd[first], traj.qdd[first])
    alone = clarabel_alone(robot, sub)
    assert alone["optimal"] == 15 and agrees(alone), alone
