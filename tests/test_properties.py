"""Property-based tests on generated robots (issue 7, item 2).

Robots come from :mod:`tests.robotgen` (chains and trees of 1-6 links, spherical and revolute joints,
random inertias, 3-6 cables per degree of freedom routed over several links, a random base
placement). On failure hypothesis prints the ``GenRobot(...)`` (Python that rebuilds it) and the
``note()``d URDF and sidecar text.

Tolerances: ``L`` against central differences 1e-7 relative (step 1e-6: truncation ~1e-12, rounding
~1e-10); identities between exact quantities 1e-9 relative; solver results as the runner checks them
(equation of motion 1e-8 relative, bounds 1e-9 N, cones 1e-6 deg) and ProxQP's objective equal to
Clarabel's to 1e-6 relative.

**Infeasibility agreement.** Near the boundary of the feasible set the two solvers can legitimately
disagree by a hair: one returns a point that breaks a bound by ~1e-9 (the runner then says
``inaccurate``) where the other proves infeasibility. So agreement is asserted as: ProxQP
``infeasible`` implies Clarabel not ``optimal``, and Clarabel ``infeasible`` implies ProxQP not
``optimal``.
"""

from __future__ import annotations

import os
import sys
import tempfile

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, note, seed, settings
from hypothesis import strategies as st

from mcdm_pin import InverseDynamics, compute_terms
from mcdm_pin.problem import Context
from mcdm_pin.settings import DEFAULT

from .fd import bounds_lp_feasible, lengths_jacobian
from .robotgen import GenRobot, robots

pytest.importorskip("clarabel")

# a fixed seed (not derandomize, whose examples change whenever a test's source changes), and
# hypothesis's pool of literals held empty (tests/conftest.py): the same examples alone and in the
# suite, whatever a worker loaded before; MCDM_HYPOTHESIS_SEED=<n> explores other examples
SEED = int(os.environ.get("MCDM_HYPOTHESIS_SEED", "20141121"))
SETTINGS = dict(deadline=None, database=None, print_blob=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                      HealthCheck.large_base_example, HealthCheck.filter_too_much])
EOM_TOL, BOUND_TOL, CONE_TOL_DEG, OBJ_RTOL = 1e-8, 1e-9, 1e-6, 1e-6


seeds = st.integers(0, 2**32 - 1)


def load(g: GenRobot, folder):
    urdf, sidecar = g.texts()
    note(f"URDF:\n{urdf}\nsidecar:\n{sidecar}")
    return g.load(folder)


def _objective_rounding(robot, case, q, qd, qdd, f) -> float:
    """What rounding leaves of ``1/2 f^T P f + c^T f + r`` at ``f``: the terms' magnitudes times 1e3
    machine epsilons (with ``r``, the squared wrench of the cables' absence, the sum cancels: at an
    optimum of zero the value is rounding, 1e-12 of forces ~200 N)."""
    inv = InverseDynamics.for_case(robot, case)
    qd, qdd = inv.evaluate.check_motion(qd, qdd)
    terms = inv.evaluate(robot.check_configuration(q), qd, qdd, checked=True)  # as the solve does
    qp = inv.problem.assemble(terms, Context(robot, None))
    f = np.asarray(f, dtype=float)
    quad = 0.5 * abs(f @ qp.gradient(f) - qp.c @ f)
    return 1e3 * np.finfo(float).eps * (quad + abs(qp.c @ f) + abs(qp.r))


def state(robot, seed, scale=0.6):
    rng = np.random.default_rng(seed)
    return (rng.uniform(-scale, scale, robot.nv), rng.normal(size=robot.nv) * 0.5,
            rng.normal(size=robot.nv) * 0.5, rng)


@seed(SEED)
@settings(max_examples=40, **SETTINGS)
@given(robots(), seeds)
def test_L_matches_central_differences(g, seed):
    with tempfile.TemporaryDirectory() as d:
        robot = load(g, d)
        q, _, _, _ = state(robot, seed)
        terms = compute_terms(robot, q)
        fd = lengths_jacobian(lambda x: compute_terms(robot, x).lengths, q)
        assert np.abs(fd - terms.L).max() <= 1e-7 * max(1.0, np.abs(terms.L).max())


@seed(SEED)
@settings(max_examples=40, **SETTINGS)
@given(robots(), seeds)
def test_joint_space_part_of_wrench_is_generalised_force(g, seed):
    """S_a^T p_a = (M qdd + h + L^T f)_a for every joint, any f (the joints are passive)."""
    with tempfile.TemporaryDirectory() as d:
        robot = load(g, d)
        q, qd, qdd, rng = state(robot, seed)
        terms = compute_terms(robot, q, qd, qdd)
        f = rng.uniform(robot.f_min, robot.f_max)
        p = terms.wrenches(f)
        expected = terms.M @ qdd + terms.h + terms.L.T @ f
        model = robot.model
        data = model.createData()
        pin.computeJointJacobians(model, data, robot.pin_q(q))
        scale = max(1.0, np.abs(expected).max(), np.abs(terms.L.T @ f).max())
        for a, joint in enumerate(robot.joints):
            J = pin.getJointJacobian(model, data, joint.child_id, pin.ReferenceFrame.LOCAL)
            S = J.reshape(6, model.nv)[:, joint.idx_v]
            assert np.abs(S.T @ p[a] - expected[joint.idx_v]).max() <= 1e-9 * scale


@seed(SEED)
@settings(max_examples=30, **SETTINGS)
@given(robots(), seeds, st.tuples(*[st.floats(-2.0, 2.0)] * 3), st.tuples(*[st.floats(-np.pi, np.pi)] * 3))
def test_wrenches_invariant_to_base_placement(g, seed, xyz, rpy):
    """Moving and turning the whole robot (gravity turned along) changes no term and no wrench."""
    with tempfile.TemporaryDirectory() as d:
        a = load(g, d + "/a")
        moved = g.moved(xyz, rpy)
        note(f"moved base: xyz={moved.base_xyz}, rpy={moved.base_rpy}")
        b = moved.load(d + "/b")
        q, qd, qdd, rng = state(a, seed)
        ta, tb = compute_terms(a, q, qd, qdd), compute_terms(b, q, qd, qdd)
        f = rng.uniform(a.f_min, a.f_max)
        wa, wb = ta.wrenches(f), tb.wrenches(f)
        scale = max(1.0, np.abs(wa).max())
        assert np.abs(wa - wb).max() <= 1e-9 * scale
        assert np.abs(ta.M - tb.M).max() <= 1e-9 * max(1.0, np.abs(ta.M).max())
        assert np.abs(ta.h - tb.h).max() <= 1e-9 * max(1.0, np.abs(ta.h).max())
        assert np.abs(ta.L - tb.L).max() <= 1e-9 * max(1.0, np.abs(ta.L).max())
        assert np.abs(ta.lengths - tb.lengths).max() <= 1e-12 * max(1.0, ta.lengths.max())


SOLVER_STATS: dict[str, int] = {}


@seed(SEED)
@settings(max_examples=100, **SETTINGS)
@given(robots(grouped=True, mass=(0.01, 0.5), f_bounds=((0.0, 1.0), (500.0, 5000.0)), base_offset=False), seeds, st.sampled_from([1, 2, 3]))
def test_solver_meets_constraints_and_agrees_with_clarabel(g, seed, case):
    with tempfile.TemporaryDirectory() as d:
        robot = load(g, d)
        if case == 3 and not any(j.cone_deg for j in robot.joints):
            case = 2
        q, qd, qdd, _ = state(robot, seed)
        prox = InverseDynamics.for_case(robot, case).solve(q, qd, qdd)
        ref = InverseDynamics.for_case(robot, case, solver="clarabel").solve(q, qd, qdd)
        note(f"case {case}: proxqp {prox.status} ({prox.message}), clarabel {ref.status} ({ref.message})")
        key = f"case {case}: {prox.status}/{ref.status}"
        SOLVER_STATS[key] = SOLVER_STATS.get(key, 0) + 1
        # the default chain has Clarabel as a fallback: an answer of that stage compared with
        # Clarabel would be Clarabel vs Clarabel, so it is counted (and bounded below), not compared
        by_clarabel = prox.stage.startswith("clarabel")
        if by_clarabel:
            key_c = f"answered by the clarabel stage ({prox.status})"
            SOLVER_STATS[key_c] = SOLVER_STATS.get(key_c, 0) + 1
            if prox.status == "infeasible" and case < 3:
                # no cones: HiGHS decides the bounds LP independently
                assert not bounds_lp_feasible(robot, q, qd, qdd)
                SOLVER_STATS["clarabel's infeasible confirmed by HiGHS"] = \
                    SOLVER_STATS.get("clarabel's infeasible confirmed by HiGHS", 0) + 1
        if prox.status == "infeasible":
            assert ref.status != "optimal"
        if ref.status == "infeasible":
            assert prox.status != "optimal"
        # ProxQP alone stalled on ~1 in 100 generated robots (51k iterations, "max_iter"); the
        # default chain answers those with its compiled interior-point method (Clarabel as the last
        # resort), so every instant gets an answer: optimal, infeasible or (checked and found
        # wanting) inaccurate
        assert prox.status in ("optimal", "infeasible", "inaccurate")
        if prox.status == "optimal":
            f = prox.f
            assert prox.eom_residual <= EOM_TOL
            assert np.all(f >= robot.f_min - BOUND_TOL) and np.all(f <= robot.f_max + BOUND_TOL)
            if case == 3:
                cones = np.array([j.cone_deg if j.cone_deg else np.inf for j in robot.joints])
                assert np.all(prox.interaction_angle_deg <= cones + CONE_TOL_DEG)
            if ref.status == "optimal" and not by_clarabel:
                # not worse than Clarabel's (ours is feasible, checked above; lower is closer to optimal),
                # beyond the objective's own rounding (at an optimum of zero its value is rounding)
                floor = (_objective_rounding(robot, case, q, qd, qdd, ref.f)
                         + _objective_rounding(robot, case, q, qd, qdd, prox.f))
                assert prox.objective - ref.objective <= OBJ_RTOL * abs(ref.objective) + floor


def test_proxqp_stall_is_answered_by_the_cascade():
    """The generated robot on which ProxQP stalled (tests/regressions.py): ProxQP alone still
    reports its iteration limit; the default chain answers (its compiled interior-point method, or
    Clarabel as the last resort) with Clarabel's optimum, checked."""
    from mcdm_pin.solvers import ProxQPSolver

    from .regressions import PROXQP_STALL, PROXQP_STALL_SEED

    with tempfile.TemporaryDirectory() as d:
        robot = PROXQP_STALL.load(d)
        q, qd, qdd, _ = state(robot, PROXQP_STALL_SEED)
        alone = InverseDynamics.for_case(robot, 2, solver=ProxQPSolver(active_set=False, fallback=False)
                                         ).solve(q, qd, qdd)
        ours = InverseDynamics.for_case(robot, 2).solve(q, qd, qdd)
        ref = InverseDynamics.for_case(robot, 2, solver="clarabel").solve(q, qd, qdd)
    assert alone.status == "max_iter"
    assert ours.status == "optimal" and not ours.stage.startswith(("proxqp", "clarabel"))
    assert ours.eom_residual <= EOM_TOL
    assert np.all(ours.f >= robot.f_min - BOUND_TOL) and np.all(ours.f <= robot.f_max + BOUND_TOL)
    assert ours.objective == pytest.approx(ref.objective, rel=OBJ_RTOL)
    # the optimum is not unique there (a flat ridge): both chains return the least-norm forces
    assert not ours.unique and not ref.unique
    assert np.abs(ours.f - ref.f).max() <= 1e-6 * np.abs(ref.f).max()


def test_generator_covers_feasible_and_infeasible_instants():
    """The solver property above is only meaningful if both outcomes occur (counts from the run)."""
    if not SOLVER_STATS:  # run alone: run the property here (it fills SOLVER_STATS)
        test_solver_meets_constraints_and_agrees_with_clarabel()
    total = sum(n for k, n in SOLVER_STATS.items() if k.startswith("case"))
    # comparisons with Clarabel that compared Clarabel with itself: few (the compiled method or
    # the active set answers the rest)
    # an optimal answer of the default chain is never Clarabel's (then the comparison above would be
    # Clarabel's with itself); its "infeasible" often is (the compiled method does not always
    # certify infeasibility): those of cases 1 and 2 were confirmed by HiGHS, those of case 3
    # (cones: no LP decides them) are bounded
    assert SOLVER_STATS.get("answered by the clarabel stage (optimal)", 0) <= 0.02 * total, SOLVER_STATS
    unconfirmed = SOLVER_STATS.get("answered by the clarabel stage (infeasible)", 0) - \
        SOLVER_STATS.get("clarabel's infeasible confirmed by HiGHS", 0)
    assert unconfirmed <= 0.15 * total, SOLVER_STATS
    optimal = sum(n for k, n in SOLVER_STATS.items() if "optimal/optimal" in k)
    infeasible = sum(n for k, n in SOLVER_STATS.items() if "infeasible/" in k)
    print(SOLVER_STATS)
    assert optimal >= 20 and infeasible >= 5, SOLVER_STATS
    stalled = sum(n for k, n in SOLVER_STATS.items() if "max_iter/" in k)
    assert stalled == 0, SOLVER_STATS
    # an "inaccurate" answer (checked and found wanting) is counted and bounded, not skipped
    inaccurate = sum(n for k, n in SOLVER_STATS.items() if k.startswith("case") and
                     k.split(": ")[1].startswith("inaccurate/"))
    assert inaccurate <= 0.02 * total, SOLVER_STATS


def test_ipm_reaches_the_optimum_where_the_scaled_objective_is_tiny():
    """The generated robot whose scaled case-1 objective is 3.5e-11 (tests/regressions.py): the compiled
    interior-point method stopped at an absolute duality gap of 1e-13, 4e-4 above the optimum, and
    called it optimal. Its gap is now relative to the objective, and its answer is Clarabel's optimum
    (the crossover makes it exact: 1e-9 covers Clarabel's own gap of 1e-11 relative and rounding)."""
    from .regressions import IPM_GAP_FLOOR, IPM_GAP_FLOOR_SEED

    with tempfile.TemporaryDirectory() as d:
        robot = IPM_GAP_FLOOR.load(d)
        q, qd, qdd, _ = state(robot, IPM_GAP_FLOOR_SEED)
        # (the interior-point method itself: a cold case-1 instant otherwise goes to the dual guess)
        ours = InverseDynamics.for_case(robot, 1, settings=DEFAULT.replace(cold_dual_steps=0)).solve(q, qd, qdd)
        dual = InverseDynamics.for_case(robot, 1).solve(q, qd, qdd)
        ref = InverseDynamics.for_case(robot, 1, solver="clarabel").solve(q, qd, qdd)
    assert ours.status == "optimal" and ref.status == "optimal" and dual.status == "optimal"
    assert ours.stage == "ipm", ours.stage
    assert dual.objective == pytest.approx(ours.objective, rel=1e-12)
    assert ours.eom_residual <= EOM_TOL
    assert ours.objective == pytest.approx(ref.objective, rel=1e-9)
    assert ours.objective <= ref.objective * (1 + 1e-12)


def test_one_dof_robot(tmp_path):
    """Regression: pin.getJointJacobian returns a 1-DoF model's 6 x 1 Jacobian as a flat (6,) array,
    which gave L the wrong shape (found by the generator; fixed in terms.py)."""
    from .robotgen import GenCable, GenLink

    g = GenRobot(links=(GenLink(parent=0, kind="revolute", xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0),
                                axis=(1.0, 0.0, 0.0), length=0.5, mass=1.0, com=(0.0, 0.0, 0.25),
                                inertia=(0.03, 0.0, 0.0, 0.03, 0.0, 0.01)),),
                 cables=(GenCable((0, 1), ((0.0, 0.25, 0.0), (0.0, 0.1, 0.4)), 0.0, 200.0),
                         GenCable((0, 1), ((0.0, -0.25, 0.0), (0.0, -0.1, 0.4)), 0.0, 200.0),
                         GenCable((0, 1), ((0.0, 0.3, 0.0), (0.0, 0.0, 0.4)), 0.0, 200.0)))
    robot = g.load(tmp_path)
    terms = compute_terms(robot, [0.1])
    assert terms.L.shape == (3, 1)
    assert InverseDynamics.for_case(robot, 1).solve([0.1]).status == "optimal"


def test_a_rounding_zero_in_the_equations_does_not_scale_the_answer_away():
    """The generated robot whose equation of motion holds -4.3e-19 for a cable through the joint's
    axis (tests/regressions.py): the scaling counts it as zero, and the default chain answers with
    Clarabel's optimum and forces."""
    from mcdm_pin.scaling import equilibrate

    from .regressions import NOISE_COLUMN, NOISE_COLUMN_SEED

    with tempfile.TemporaryDirectory() as d:
        robot = NOISE_COLUMN.load(d)
        q, qd, qdd, _ = state(robot, NOISE_COLUMN_SEED)
        ours = InverseDynamics.for_case(robot, 2).solve(q, qd, qdd)
        ref = InverseDynamics.for_case(robot, 2, solver="clarabel").solve(q, qd, qdd)
    assert ours.status == ref.status == "optimal"
    assert ours.objective == pytest.approx(ref.objective, rel=OBJ_RTOL)
    assert np.abs(ours.f - ref.f).max() <= 1e-6 * np.abs(ref.f).max()
    # the rounding of a zero beside O(0.06) entries leaves its column's factor alone
    _, dcol = equilibrate(np.array([[-4.3e-19, 6.3e-2, -5.2e-2]]))
    assert dcol[0] == 1.0 and np.all(dcol[1:] > 1.0)


def test_a_negligible_weight_does_not_pin_the_least_norm_face():
    """The generated robot whose moment weight is 3e-277 beside force weights of 1, at an optimum
    of zero (tests/regressions.py): the default chain, Clarabel and ProxQP return the same least-norm
    forces (the least |f| of the three answers they gave before, 623, 637 and 73 N)."""
    from .regressions import TINY_WEIGHT, TINY_WEIGHT_SEED

    with tempfile.TemporaryDirectory() as d:
        robot = TINY_WEIGHT.load(d)
        q, qd, qdd, _ = state(robot, TINY_WEIGHT_SEED)
        answers = [InverseDynamics.for_case(robot, 2, solver=s).solve(q, qd, qdd)
                   for s in ("default", "clarabel", "proxqp")]
    assert all(a.status == "optimal" for a in answers)
    ref = answers[0].f
    for a in answers[1:]:
        assert np.abs(a.f - ref).max() <= 1e-6 * np.abs(ref).max(), (a.stage, a.f, ref)
    assert np.linalg.norm(ref) <= 73.0


def test_examples_do_not_depend_on_the_modules_loaded(tmp_path, monkeypatch):
    """A fixed seed gives the same examples alone and inside the suite: the draws of a seeded test
    are equal before and after a new local module full of literals is imported (hypothesis mixes
    the literals of the local modules loaded so far into its draws; tests/conftest.py stops that)."""
    def draws():
        seen = []

        @seed(SEED)
        @settings(max_examples=200, **SETTINGS)
        @given(st.floats(0.0, 1.0), st.integers(0, 2**32 - 1), st.floats(500.0, 5000.0))
        def record(x, n, y):
            seen.append((x, n, y))

        record()
        return seen

    before = draws()
    literals = ", ".join(f"{0.5 + k * 1e-3!r}, {k * 7919}, {600.0 + k!r}" for k in range(200))
    (tmp_path / "literal_probe.py").write_text(f"LITERALS = ({literals})\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    import literal_probe  # noqa: F401  (its literals are what a scan of the loaded modules would find)

    try:
        after = draws()
    finally:
        del sys.modules["literal_probe"]
    assert after == before
