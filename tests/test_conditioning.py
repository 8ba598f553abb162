"""Singularities and conditioning (issue 7, item 4): gimbal lock, zero-length cables, lost wrench
closure, and badly scaled robots (grams next to tonnes, millimetres next to metres, 1e-3 N next to
1e4 N) that must still meet the runner's tolerances."""

from __future__ import annotations

import os
import tempfile

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, note, seed, settings
from hypothesis import strategies as st

from mcdm_pin import InverseDynamics, Robot, StateError, TrajectoryError, compute_terms
from mcdm_pin.conditioning import euler_singularity, wrench_closure
from mcdm_pin.scaling import ScaledSolver
from mcdm_pin.trajectory import quintic_trajectory
from mcdm_pin.validation import validation_report

from .conftest import TWO_LINK, TWO_LINK_URDF
from .robotgen import robots

SEED = int(os.environ.get("MCDM_HYPOTHESIS_SEED", "20141121"))


def variant(tmp_path, edit) -> Robot:
    data = yaml.safe_load(TWO_LINK.read_text())
    data["urdf"] = str(TWO_LINK_URDF)
    edit(data)
    path = tmp_path / "variant.yaml"
    path.write_text(yaml.safe_dump(data))
    return Robot.load(path)


# ------------------------------------------------------------------------------------ gimbal lock
@pytest.mark.parametrize("q2", [np.pi / 2, np.pi / 2 - 5e-4, -np.pi / 2 + 1e-4])
def test_trajectory_reaching_gimbal_lock_is_refused_by_name(two_link, q2):
    with pytest.raises(TrajectoryError, match=r"joint 'shoulder'.*gimbal lock.*\|cos q2\|"):
        quintic_trajectory(two_link, [0.3, 0.0, 0.2, 0.0], [0.3, q2, 0.2, 0.0], 1.0, 0.01)


def test_trajectory_near_but_clear_of_gimbal_lock_is_accepted(two_link):
    traj = quintic_trajectory(two_link, [0.3, 0.0, 0.2, 0.0], [0.3, 1.5, 0.2, 0.0], 1.0, 0.01)
    margin = min(euler_singularity(two_link, q)["shoulder"] for q in traj.q)
    assert margin == pytest.approx(np.cos(1.5), rel=1e-9)  # 0.0707 > 1e-3


def test_euler_singularity_margin_is_cos_q2(two_link):
    assert euler_singularity(two_link, [0.4, 0.7, -0.2, 0.1])["shoulder"] == pytest.approx(np.cos(0.7))


# -------------------------------------------------------------------------- zero-length cables
def test_zero_length_cable_segment_is_a_state_error_naming_the_cable(tmp_path):
    def edit(d):  # cable1 from the ball's centre to the ball's centre on link 1: zero length always
        d["cables"][0]["route"] = [{"link": "base", "point": [0, 0, 0]}, {"link": "link1", "point": [0, 0, 0]}]

    robot = variant(tmp_path, edit)
    with pytest.raises(StateError, match="cable 'cable1': a segment has zero length"):
        compute_terms(robot, np.zeros(4))
    with pytest.raises(StateError, match="cable1"):
        InverseDynamics.for_case(robot, 1).solve(np.zeros(4))
    report = dict((t, lvl) for lvl, t in validation_report(robot))
    assert any("cannot evaluate the model at q = 0" in t and "cable1" in t for t in report)


def test_cable_through_its_joint_point_has_no_lever_and_closure_says_so(tmp_path):
    """All four shoulder cables start at the ball's centre: they pass through the joint point, so
    they cannot turn link 1 about it; closure names the shoulder."""
    def edit(d):
        for c in d["cables"][:4]:
            c["route"][0]["point"] = [0.0, 0.0, 0.0]

    robot = variant(tmp_path, edit)
    terms = compute_terms(robot, np.array([0.1, 0.2, 0.0, 0.1]))
    closure = wrench_closure(robot, terms.q, terms.L)
    assert not closure.closed and "shoulder" in closure.message


def test_lost_wrench_closure_is_diagnosed(tmp_path, two_link):
    # without cables 5-8 nothing acts on the elbow
    robot = variant(tmp_path, lambda d: d.__setitem__("cables", d["cables"][:4]))
    c = wrench_closure(robot, [0.1, 0.2, 0.3, 0.1])
    assert not c.closed and c.rank == 3 and "elbow" in c.message and "q4_x" in c.message
    assert any(lvl == "warn" and "wrench closure lost" in t for lvl, t in validation_report(robot))
    res = InverseDynamics.for_case(robot, 1).solve([0.1, 0.2, 0.3, 0.1], np.zeros(4), np.ones(4))
    assert res.status == "infeasible" and res.message.startswith("bounds")
    # the 2-link arm itself at q = 0: no cable twists link 1 (q3), the reason trajectory 2 is
    # infeasible at t = 0
    c0 = wrench_closure(two_link, np.zeros(4))
    assert not c0.closed and "q3_z" in c0.message


# ------------------------------------------------------------------------------------- scaling
SCALED_STATS: dict[str, int] = {}


BADLY_SCALED_SETTINGS = dict(max_examples=60, deadline=None, database=None,
                             suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                                    HealthCheck.filter_too_much, HealthCheck.large_base_example])


def badly_scaled(f_max: float):
    """(robot, seed, case): masses 1 g .. 1 t, lengths 1 mm .. 0.95 m, forces in [1e-3, f_max] N."""
    return (robots(min_links=2, max_links=4, grouped=True, mass=(1.0, 1.0), mass_log_spread=3.0,
                   length=(0.03, 0.03), length_log_spread=1.5, f_bounds=((1e-3, 1e-3), (f_max, f_max)),
                   base_offset=False), st.integers(0, 2**32 - 1), st.sampled_from([1, 2, 3]))


def solve_both(g, sd, case, tmp):
    """The generated robot loaded into ``tmp``, the case actually solved (3 falls back to 2 without
    cones), and its instant at a random state solved by the default back-end and by Clarabel."""
    urdf, sidecar = g.texts()
    note(f"URDF:\n{urdf}\nsidecar:\n{sidecar}")
    robot = g.load(tmp)
    if case == 3 and not any(j.cone_deg for j in robot.joints):
        case = 2
    rng = np.random.default_rng(sd)
    q, qd, qdd = rng.uniform(-0.6, 0.6, robot.nv), 0.5 * rng.normal(size=robot.nv), 0.5 * rng.normal(size=robot.nv)
    ident = InverseDynamics.for_case(robot, case)
    assert isinstance(ident.solver, ScaledSolver)
    prox = ident.solve(q, qd, qdd)
    ref = InverseDynamics.for_case(robot, case, solver="clarabel").solve(q, qd, qdd)
    note(f"case {case}: proxqp {prox.status} ({prox.message}); clarabel {ref.status} ({ref.message})")
    return robot, prox, ref


@seed(SEED)
@settings(**BADLY_SCALED_SETTINGS)
@given(*badly_scaled(1e6))
def test_badly_scaled_robots_meet_the_tolerances(g, sd, case):
    """Masses 1 g .. 1 t (log-uniform), lengths 1 mm .. 0.95 m, f in [1e-3, 1e6] N: ProxQP's answers,
    through :class:`~mcdm_pin.scaling.ScaledSolver`, meet the runner's tolerances (equation of motion
    1e-8 relative, bounds 1e-9 N absolute, cones 1e-6 deg) and Clarabel's objective to 1e-6.

    Without scaling, ProxQP stopped at its iteration limit on 23 of 85 such instants (measured with
    the solver of commit c4218ec, each costing seconds of retries); InverseDynamics wraps every
    back-end in ScaledSolver (docs/trust.md)."""
    with tempfile.TemporaryDirectory() as d:
        robot, prox, ref = solve_both(g, sd, case, d)
        key = f"{prox.status}/{ref.status}"
        SCALED_STATS[key] = SCALED_STATS.get(key, 0) + 1
        # a failure to answer (max_iter, inaccurate) is counted, not asserted per example: the
        # generated examples depend on the modules loaded (hypothesis mines their constants), and a
        # rare stall must not send hypothesis shrinking for minutes; the rate is asserted below
        if prox.status not in ("optimal", "infeasible") and ref.status == "optimal":
            SCALED_STATS["proxqp failed, clarabel solved"] = SCALED_STATS.get("proxqp failed, clarabel solved", 0) + 1
        SCALED_STATS["examples"] = SCALED_STATS.get("examples", 0) + 1
        # an answer of the default chain's Clarabel stage compared with Clarabel compares Clarabel
        # with itself: counted (bounded below), not compared
        by_clarabel = prox.stage.startswith("clarabel")
        if by_clarabel:
            key_c = f"answered by the clarabel stage ({prox.status})"
            SCALED_STATS[key_c] = SCALED_STATS.get(key_c, 0) + 1
        if prox.status == "infeasible":
            assert ref.status != "optimal"
        if prox.status == "optimal":
            f = prox.f
            assert prox.eom_residual <= 1e-8
            assert np.all(f >= robot.f_min - 1e-9) and np.all(f <= robot.f_max + 1e-9)
            if ref.status == "optimal" and "AlmostSolved" not in ref.message and not by_clarabel:
                # where Clarabel reached full accuracy the two agree; its reduced-accuracy
                # ("AlmostSolved") answers are no reference (seen: 3 % worse, and 5.6e-6 better at
                # a point 1e5 times larger on a flat optimal ridge)
                # relative 1e-6, but where the optimum lies at the end of a nearly flat ridge (PSD
                # objective) the two answers differ by orders of magnitude (seen: 7 N against 1e5 N,
                # objectives 2.5e-6 apart; with MCDM_HYPOTHESIS_SEED=3, hundreds of N against up to
                # 1e6 N = f_max, 4.8e-6 apart) and the KKT check's gradient tolerance bounds the objective only to
                # ~1e-9 |f|^2: known gap, docs/trust.md
                big = max(1.0, np.abs(f).max(), np.abs(ref.f).max())
                scale = max(abs(ref.objective), 1e-9 * big ** 2)
                # one-sided: ours may be lower (both points are feasible, checked above; on
                # badly scaled robots Clarabel's own answer was seen 2.2e-6 above ours), never higher
                assert prox.objective - ref.objective <= 1e-6 * scale
            masses = [link.mass for link in g.links]
            lengths = [link.length for link in g.links]
            for name, wide in (("masses 1e3 apart", max(masses) / min(masses) > 1e3),
                               ("lengths 1e2 apart", max(lengths) / min(lengths) > 1e2),
                               ("forces 1e6 apart", f.max() / f.min() > 1e6)):
                SCALED_STATS[name] = SCALED_STATS.get(name, 0) + int(wide)


@seed(SEED)
@settings(**BADLY_SCALED_SETTINGS)
@given(*badly_scaled(1e4))
def test_issue_range_objective_matches_clarabel_strictly(g, sd, case):
    """The issue's range, forces of 1e-3 N next to 1e4 N (masses 1 g .. 1 t, lengths 1 mm .. 0.95 m):
    besides the runner's tolerances, the objective is not above Clarabel's by more than 1e-6 relative, without the
    size-relative allowance the 1e6 N test needs on long flat ridges (docs/trust.md, "Known gap";
    the same strict check also passed with MCDM_HYPOTHESIS_SEED=1, 2, 3 and 4)."""
    with tempfile.TemporaryDirectory() as d:
        robot, prox, ref = solve_both(g, sd, case, d)
        by_clarabel = prox.stage.startswith("clarabel")  # then the comparison would be Clarabel's with itself
        if prox.status == "infeasible":
            assert ref.status != "optimal"
        if prox.status == "optimal":
            assert prox.eom_residual <= 1e-8
            assert np.all(prox.f >= robot.f_min - 1e-9) and np.all(prox.f <= robot.f_max + 1e-9)
            if ref.status == "optimal" and "AlmostSolved" not in ref.message and not by_clarabel:
                # not worse than Clarabel (a lower objective at a feasible point is closer to the optimum)
                assert prox.objective - ref.objective <= 1e-6 * max(abs(ref.objective), 1e-12)


def test_scaled_examples_are_really_badly_scaled():
    if not SCALED_STATS:  # run alone: run the property here (it fills SCALED_STATS)
        test_badly_scaled_robots_meet_the_tolerances()
    print(SCALED_STATS)
    # which badly scaled features the examples hit depends on the modules loaded (hypothesis mines
    # their constants); the deterministic robot below covers all of them every time
    assert sum(SCALED_STATS.get(name, 0) for name in ("masses 1e3 apart", "lengths 1e2 apart",
                                                       "forces 1e6 apart")) >= 1, SCALED_STATS
    # measured with ScaledSolver: 0 of 150 run alone, a few per cent in the full suite (other examples)
    failed = SCALED_STATS.get("proxqp failed, clarabel solved", 0)
    assert failed <= 0.1 * SCALED_STATS["examples"], SCALED_STATS
    # comparisons that were Clarabel against itself (the default chain's Clarabel stage answered)
    # the default chain's optimal answers are not Clarabel's (that comparison would be Clarabel's with
    # itself); its infeasible ones often are (tests/test_properties.py checks those with HiGHS)
    assert SCALED_STATS.get("answered by the clarabel stage (optimal)", 0) <= 0.05 * SCALED_STATS["examples"], \
        SCALED_STATS


def test_grams_tonnes_millimetres_and_meganewtons(tmp_path):
    """The 2-link arm with link 1 of 1 g (inertia 1e-6 kg m^2) and link 2 of 1 t, cables 1-4 on
    millimetre lever arms (1.5 mm on the base, 0.5 mm on link 1), every cable in [1e-3, 1e6] N:
    trajectory 1, cases 1-3, against Clarabel."""
    from mcdm_pin import load_trajectory

    from .conftest import REPO
    src = (REPO / "urdf" / "two_link_sr.urdf").read_text()
    head, tail = src.split('<link name="link2">')
    unit = 'ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"'
    head = head.replace('<mass value="0.1"/>', '<mass value="0.001"/>').replace(
        unit, 'ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"')
    tail = tail.replace('<mass value="0.1"/>', '<mass value="1000"/>').replace(
        unit, 'ixx="10" ixy="0" ixz="0" iyy="10" iyz="0" izz="10"')
    (tmp_path / "u.urdf").write_text(head + '<link name="link2">' + tail)
    sc = yaml.safe_load((REPO / "robots" / "two_link_sr.yaml").read_text())
    sc["urdf"] = "u.urdf"
    for c in sc["cables"][:4]:
        c["route"][0]["point"] = [0.01 * x for x in c["route"][0]["point"]]
        c["route"][1]["point"] = [0.01 * x for x in c["route"][1]["point"][:2]] + [0.002]
    for c in sc["cables"]:
        c["f_min"], c["f_max"] = 1e-3, 1e6
    (tmp_path / "r.yaml").write_text(yaml.safe_dump(sc))
    robot = Robot.load(tmp_path / "r.yaml")
    traj = load_trajectory(robot, "traj1").subsample(51)
    for case in (1, 2, 3):
        # (no diagnosis of infeasible instants: case 3 has many, and their analysis is not tested here)
        ours = InverseDynamics.for_case(robot, case, diagnose=False).solve_trajectory(traj, progress=False)
        ref = InverseDynamics.for_case(robot, case, solver="clarabel", diagnose=False).solve_trajectory(
            traj, progress=False)
        assert set(ours.status) <= {"optimal", "infeasible"}
        # Clarabel may end "inaccurate" (reduced accuracy) where we are optimal, never the reverse
        assert np.all(ref.status[ours.status == "infeasible"] == "infeasible")
        ok = ours.found
        assert np.all(ours.eom_residual[ok] <= 1e-8)
        assert np.all(ours.f[ok] >= 1e-3 - 1e-9) and np.all(ours.f[ok] <= 1e6 + 1e-9)
        assert np.nanmax(ours.f) > 1e5 and np.nanmin(ours.f) == pytest.approx(1e-3)  # 1e8 apart
        both = ok & (ref.status == "optimal")
        rel = np.abs(ours.objective[both] - ref.objective[both]) / np.abs(ref.objective[both])
        assert rel.max() <= 1e-6
