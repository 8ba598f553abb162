"""The benchmark's correctness check (no timings): on the 2-link arm, mcdm-pin and the Clarabel peer
reach the reference optimum in every case."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_id.py"


@pytest.fixture(scope="module")
def bench():
    pytest.importorskip("clarabel")  # the reference of the check
    spec = importlib.util.spec_from_file_location("bench_id", BENCH)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["bench_id"] = mod
    spec.loader.exec_module(mod)
    return mod


def test_check_two_link_clarabel(bench, capsys):
    code = bench.main(["--robot", "two_link", "--check-only", "--peers", "clarabel", "--check", "7"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "every back-end reached the reference optimum" in out
    for case in (1, 2, 3):
        assert f"case {case}: ours ok, clarabel ok" in out


def test_check_detects_a_wrong_answer(bench):
    """The check is not vacuous: a point off the optimum, or breaking a constraint, fails it."""
    import numpy as np

    from mcdm_pin import InverseDynamics, Robot, load_trajectory
    from mcdm_pin.problem import Context

    robot = Robot.load(bench.REPO / "robots" / "two_link_sr.yaml")
    traj = load_trajectory(robot, "traj1")
    ident = InverseDynamics.for_case(robot, 3)
    qp = ident.problem.assemble(ident.evaluate(traj.q[20], traj.qd[20], traj.qdd[20]), Context(robot))
    ref = bench.reference_solve(qp)
    assert bench.check_solution(qp, ref, qp.objective(ref))[0]
    # feasible for the equation of motion and bounds but not optimal: push along the null space of A
    null = np.linalg.svd(qp.A)[2][-1]
    assert not bench.check_solution(qp, ref + 1.0 * null * np.sign(null.sum()), qp.objective(ref))[0]
    assert not bench.check_solution(qp, ref * 1.01, qp.objective(ref))[0]  # breaks the equation of motion
    assert not bench.check_solution(qp, None, qp.objective(ref))[0]


def test_missing_peer_is_skipped(bench, monkeypatch):
    """A peer that is not installed is skipped with an install note, not an error."""
    def missing():
        raise ImportError("no module", name="cyipopt")

    monkeypatch.setitem(bench.PEER_CLASSES, "ipopt", missing)
    peers, notes = bench.make_peers(["ipopt"])
    assert peers == [] and "ipopt: skipped" in notes[0] and "coinor-libipopt-dev" in notes[0]


def test_the_arm_benchmark_checks_both_back_ends_and_splits_the_first_warm_frame(bench, capsys):
    """``benchmarks/myoarm.py`` on MyoSuite's arm, case 3, one run: both back-ends pass the check
    against Clarabel at 1e-11, every instant is answered, and the warm frames after each run's first
    (which has no previous answer) are reported apart, and among them those whose optimum is a face
    (what is printed is checked, not the times)."""
    pytest.importorskip("mujoco")
    spec = importlib.util.spec_from_file_location("myoarm_bench", BENCH.parent / "myoarm.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.main(["--case", "3", "--repeat", "1", "--check", "2"]) == 0
    out = capsys.readouterr().out
    rows = [line.split(" | ") for line in out.splitlines() if line.startswith("| 3 | ")]
    assert len(rows) == 4 and all(r[-2] == "0" and r[-1].rstrip(" |") == "ok" for r in rows), rows
    assert "Case 3, warm frames after each run's first (p50 / p99 wall, ms): ours " in out
    # about a third of the arm's frames have a face of optima (33 of 101 here): reported apart
    face = [line for line in out.splitlines() if line.startswith("Case 3, ours, those frames whose optimum is a face")]
    assert len(face) == 1, face
    n_face = int(face[0].split("): ")[1].split(" of 100, ")[0])
    assert 20 <= n_face <= 45, face
