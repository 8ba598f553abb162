"""Workspaces: poses, the per-pose answers and margins, the Zarr store, resume, the command line."""

from __future__ import annotations

import re

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot
from mcdm_pin.cli import main
from mcdm_pin.workspace import (Grid, PosesFile, PoseSolver, RandomPoses, Setup, WorkspaceError, as_grid,
                                compute_workspace, open_workspace)
from mcdm_pin.workspace import margins
from mcdm_pin.workspace.store import RESULT_VARIABLES

from .conftest import TWO_LINK


def assert_same_store(a, b, exact=False):
    """Two stores hold the same statuses, labels and settings, and the same numbers (NaN where the
    other has NaN). Between processes the last bits may differ (vectorised sums round by memory
    alignment; seen: 4e-12 relative on a case-3 force), so unless ``exact`` the numbers agree to
    1e-9 (relative and N or deg), and the cone margin to its bisection tolerance."""
    assert a.attrs == b.attrs
    assert set(a.variables) == set(b.variables)
    for name in a.variables:
        x, y = a[name].values, b[name].values
        if x.dtype.kind != "f":
            assert (x == y).all(), name
        elif exact:
            np.testing.assert_array_equal(x, y, err_msg=name)  # NaN == NaN here
        else:
            atol = margins.CONE_TOL_DEG if name == "needed_cone_deg" else 1e-9
            np.testing.assert_allclose(x, y, rtol=1e-9, atol=atol, err_msg=name)


# ------------------------------------------------------------------------------------------ poses
def test_grid_runs_in_c_order_with_fixed_coordinates(two_link):
    g = Grid(two_link, {"q1_x": (-1.0, 1.0, 3), "q4_x": (0.0, 0.5, 2)}, at={"q2_y": 0.25})
    assert len(g) == 6 and g.shape == (3, 2)
    q = g.all()
    np.testing.assert_array_equal(q[:, 0], [-1, -1, 0, 0, 1, 1])
    np.testing.assert_array_equal(q[:, 3], [0, 0.5, 0, 0.5, 0, 0.5])
    np.testing.assert_array_equal(q[:, 1], 0.25)
    np.testing.assert_array_equal(q[:, 2], 0.0)
    np.testing.assert_array_equal(g.chunk(2, 5), q[2:5])
    assert g.describe()["axes"][1] == dict(coordinate="q4_x", lo=0.0, hi=0.5, n=2)


def test_random_poses_do_not_depend_on_the_chunking(two_link):
    p = RandomPoses(two_link, 100, seed=7, ranges={"q1_x": (-0.5, 0.5)}, at={"q3_z": 0.1})
    q = p.all()
    np.testing.assert_array_equal(np.vstack([p.chunk(0, 37), p.chunk(37, 100)]), q)
    np.testing.assert_array_equal(RandomPoses(two_link, 100, seed=7, ranges={"q1_x": (-0.5, 0.5)},
                                              at={"q3_z": 0.1}).chunk(50, 60), q[50:60])
    assert not np.array_equal(RandomPoses(two_link, 100, seed=8).all()[:, 1], q[:, 1])
    assert q[:, 0].min() >= -0.5 and q[:, 0].max() <= 0.5 and np.ptp(q[:, 0]) > 0.8
    np.testing.assert_array_equal(q[:, 2], 0.1)
    # without a range: the URDF's joint limits (+-3.1416 on the arm)
    assert q[:, 3].min() >= -3.1416 and q[:, 3].max() <= 3.1416 and np.ptp(q[:, 3]) > 5.0


def test_random_poses_need_a_range_where_there_is_no_joint_limit():
    robot = Robot.load(TWO_LINK)
    robot.model.upperPositionLimit[:] = np.inf
    with pytest.raises(WorkspaceError, match=r"q1_x, q2_y, q4_x have no finite joint limit; give"):
        RandomPoses(robot, 10, at={"q3_z": 0.0})
    assert len(RandomPoses(robot, 10, ranges={c: (-1, 1) for c in robot.coordinate_names})) == 10


def test_poses_file_with_a_header_of_some_coordinates(two_link, tmp_path):
    path = tmp_path / "poses.csv"
    path.write_text("q4_x,q1_x\n0.1,0.2\n\n0.3,0.4\n")
    p = PosesFile(two_link, path, at={"q2_y": -0.5})
    np.testing.assert_array_equal(p.all(), [[0.2, -0.5, 0, 0.1], [0.4, -0.5, 0, 0.3]])
    path.write_text("1,2,3,4\n5,6,7,8\n")  # no header: every coordinate in order
    np.testing.assert_array_equal(PosesFile(two_link, path).all(), [[1, 2, 3, 4], [5, 6, 7, 8]])


@pytest.mark.parametrize("text, match", [
    ("q1_x,elbow\n1,2\n", r"header column 2: unknown coordinate 'elbow'; expected one of q1_x, q2_y"),
    ("q1_x,q4_x\n1,2\n3\n", r"pose 2: expected 2 numbers \(q1_x, q4_x\), got 1"),
    ("q1_x\nnan\n", r"pose 1: expected finite numbers"),
    ("q1_x\n", r"no poses in the file \(only a header\)"),
])
def test_poses_file_errors_name_the_line_and_what_was_expected(two_link, tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(WorkspaceError, match=match):
        PosesFile(two_link, path)


@pytest.mark.parametrize("make, match", [
    (lambda r: Grid(r, {"q9": (0, 1, 3)}), r"grid: unknown coordinate 'q9'; expected one of q1_x, q2_y, q3_z, q4_x"),
    (lambda r: Grid(r, {"q1_x": (1, 0, 3)}), r"grid q1_x: expected LO < HI"),
    (lambda r: Grid(r, {"q1_x": (0, 1, 2.5)}), r"positive whole number of points"),
    (lambda r: Grid(r, {"q1_x": (0, 1, 3)}, at={"q1_x": 0.0}), r"'q1_x' is also varied"),
    (lambda r: RandomPoses(r, 0), r"positive number of poses"),
])
def test_bad_pose_sets_are_refused_in_one_line(two_link, make, match):
    with pytest.raises(WorkspaceError, match=match):
        make(two_link)


# ------------------------------------------------------------------------------ answers, margins
def test_each_pose_is_the_cold_answer_of_solve(two_link):
    """A chunk's answers equal InverseDynamics.solve on a new solver for each pose, bit for bit,
    whatever poses precede it in the chunk."""
    q = Grid(two_link, {"q1_x": (-0.9, 0.9, 4), "q4_x": (-1.0, 1.0, 3)}).all()
    out = PoseSolver(two_link, Setup(case=2, margins=False)).solve(q[::-1])
    z = np.zeros(4)
    for k, pose in enumerate(q[::-1]):
        res = InverseDynamics.for_case(two_link, 2, diagnose=False).solve(pose, z, z)
        assert out["status"][k] == res.status
        np.testing.assert_array_equal(out["f"][k], res.f)
        np.testing.assert_array_equal(out["objective"][k], res.objective)
        np.testing.assert_array_equal(out["interaction_wrench"][k], res.interaction_wrench)
        np.testing.assert_array_equal(out["interaction_angle_deg"][k], res.interaction_angle_deg)
    assert set(out["status"]) == {"optimal", "infeasible"}


def test_needed_f_max_is_the_smallest_common_bound(two_link):
    """Checked by an independent LP feasibility test just above and below the reported bound."""
    from scipy.optimize import linprog

    solver = PoseSolver(two_link, Setup(case=1))

    def feasible(qp, t):
        res = linprog(np.zeros(qp.n), A_eq=qp.A, b_eq=qp.b, bounds=[(lo, t) for lo in qp.lb],
                      method="highs")
        return res.status == 0

    for pose in ([0.3, 0.0, 0.0, 0.9], [-0.6, 0.2, 0.0, 0.3], [1.2, 0.0, 0.0, 2.0]):
        qp = solver.assemble(np.array(pose))
        need = margins.needed_f_max(qp)
        assert np.isfinite(need) and need > 0.001
        assert feasible(qp, need * (1 + 1e-7)) and not feasible(qp, need * (1 - 1e-4))


def test_needed_cone_deg_is_where_the_pose_becomes_feasible(two_link):
    """On both sides of the problem's 30 deg cone: the pose solves with a cone just above the margin
    and not just below it."""
    solver = PoseSolver(two_link, Setup(case=3, cones={"shoulder": 30.0}))
    tol = margins.CONE_TOL_DEG
    for pose, inside in (([-0.6, 0.0, 0.0, 0.3], True), ([-2.3562, 0.0, 0.0, 1.5708], False)):
        qp = solver.assemble(np.array(pose))
        need = margins.needed_cone_deg(qp, solver.ident.solver)
        assert (need <= 30.0) == inside and 1.0 < need < 89.0
        for angle, ok in ((need + 2 * tol, True), (need - 0.05, False)):
            status = InverseDynamics.for_case(two_link, 3, cones={"shoulder": angle}, diagnose=False) \
                .solve(np.array(pose), np.zeros(4), np.zeros(4)).status
            assert (status == "optimal") == ok, (pose, angle, status)


def test_a_native_ball_joint_is_varied_through_its_rotation_vector(two_link):
    """The arm with a native ball joint (rotation-vector coordinates) gives the Euler-angle arm's
    answers and margins at the same rotations (about x only, where the two coordinates agree)."""
    from .conftest import REPO

    ball = Robot.load(REPO / "robots" / "two_link_sr_ball.yaml")
    setup = Setup(case=3, cones={"shoulder": 30.0})
    grid = {"q1_x": (-0.9, 0.9, 3), "q4_x": (-0.3, 0.3, 2)}
    a = PoseSolver(ball, setup).solve(Grid(ball, {"shoulder_ball.rx": grid["q1_x"],
                                                  "q4_x": grid["q4_x"]}).all())
    b = PoseSolver(two_link, setup).solve(Grid(two_link, grid).all())
    assert list(a["status"]) == list(b["status"]) and "optimal" in set(a["status"])
    np.testing.assert_allclose(a["f"], b["f"], atol=1e-9)
    np.testing.assert_allclose(a["needed_f_max"], b["needed_f_max"], rtol=1e-9)
    np.testing.assert_allclose(a["needed_cone_deg"], b["needed_cone_deg"], atol=margins.CONE_TOL_DEG)


# --------------------------------------------------------------------------------------- store
@pytest.fixture(scope="module")
def small_store(tmp_path_factory, two_link):
    path = tmp_path_factory.mktemp("ws") / "arm.zarr"
    poses = Grid(two_link, {"q1_x": (-1.2, 1.2, 5), "q4_x": (-1.5, 1.5, 4)}, at={"q2_y": 0.1})
    report = compute_workspace(two_link, poses, path, Setup(case=1), chunk=6, scheduler="inline",
                               progress=False)
    return path, poses, report


def test_store_opens_with_xarray_with_the_variables_of_the_issue(small_store, two_link):
    import xarray as xr

    path, poses, report = small_store
    assert (report.computed_chunks, report.chunks, report.computed_poses) == (4, 4, 20)
    ds = xr.open_zarr(path)
    dims = {name: ds[name].dims for name in ds.data_vars}
    assert dims == dict(q=("pose", "coordinate"), status=("pose",), objective=("pose",),
                        f=("pose", "cable"), needed_f_max=("pose",), needed_cone_deg=("pose",),
                        interaction_angle_deg=("pose", "joint"),
                        interaction_wrench=("pose", "joint", "component"), chunk_done=("chunk",))
    assert list(ds["cable"].values) == list(two_link.cable_names)
    assert list(ds["coordinate"].values) == list(two_link.coordinate_names)
    np.testing.assert_array_equal(ds["q1_x"].values, np.linspace(-1.2, 1.2, 5))
    np.testing.assert_array_equal(ds["q4_x"].values, np.linspace(-1.5, 1.5, 4))
    np.testing.assert_array_equal(ds["q"].values, poses.all())
    assert ds["f"].attrs["units"] == "N" and ds["needed_cone_deg"].attrs["units"] == "deg"
    assert ds.chunks["pose"] == (6, 6, 6, 2)
    s = ds.attrs["workspace"]
    assert s["setup"]["case"] == 1 and s["chunk"] == 6 and s["poses"]["at"] == {"q2_y": 0.1}
    assert s["robot"]["name"] == "two_link_sr" and s["start"].startswith("cold")
    # case 1: no cones, so no cone margin; the bound margin agrees with the statuses
    assert np.isnan(ds["needed_cone_deg"].values).all()
    ok = ds["status"].values == "optimal"
    assert 0 < ok.sum() < 20
    assert (ds["needed_f_max"].values[ok] <= 1000.0).all() and (ds["needed_f_max"].values[~ok] > 1000.0).all()
    g = as_grid(ds)
    assert g["status"].dims == ("q1_x", "q4_x") and g["f"].sizes == dict(cable=8, q1_x=5, q4_x=4)
    assert g["status"].values[2, 1] == ds["status"].values[2 * 4 + 1]


def test_the_chunk_size_does_not_change_the_answers(small_store, two_link, tmp_path):
    path, poses, _ = small_store
    other = tmp_path / "other.zarr"
    compute_workspace(two_link, poses, other, Setup(case=1), chunk=7, scheduler="inline", progress=False)
    a, b = open_workspace(path), open_workspace(other)
    for name in RESULT_VARIABLES:  # in one process: bit for bit
        x, y = a[name].values, b[name].values
        assert (x == y).all() if x.dtype.kind == "U" else np.array_equal(x, y, equal_nan=True), name


def test_an_existing_store_is_refused_or_resumed_only_with_its_own_settings(small_store, two_link):
    path, poses, _ = small_store
    with pytest.raises(WorkspaceError, match=r"already exists; give --resume"):
        compute_workspace(two_link, poses, path, Setup(case=1), chunk=6, scheduler="inline")
    with pytest.raises(WorkspaceError, match=r"made with other settings \(differing: chunk\)"):
        compute_workspace(two_link, poses, path, Setup(case=1), chunk=5, scheduler="inline", resume=True)
    with pytest.raises(WorkspaceError, match=r"\(differing: cones_deg, problem, setup\)|\(differing: problem, setup\)"):
        compute_workspace(two_link, poses, path, Setup(case=2), chunk=6, scheduler="inline", resume=True)
    again = compute_workspace(two_link, poses, path, Setup(case=1), chunk=6, scheduler="inline", resume=True)
    assert again.computed_chunks == 0


def test_resume_computes_only_the_missing_chunks(small_store, two_link, tmp_path):
    import shutil

    import zarr

    path, poses, _ = small_store
    copy = tmp_path / "copy.zarr"
    shutil.copytree(path, copy)
    g = zarr.open_group(str(copy), mode="r+", zarr_format=2)
    g["chunk_done"][1] = 0
    g["chunk_done"][3] = 0
    g["f"][6:12] = -1.0  # a chunk half written when the run died
    (copy / "f" / "0.0.abc.partial").write_bytes(b"torn")  # and Zarr's unfinished temporary file
    report = compute_workspace(two_link, poses, copy, Setup(case=1), chunk=6, scheduler="inline",
                               resume=True)
    assert (report.computed_chunks, report.computed_poses) == (2, 8)
    assert not list(copy.rglob("*.partial"))
    assert_same_store(open_workspace(copy), open_workspace(path), exact=True)  # one process


# ---------------------------------------------------------------------------------- command line
def test_command_line_writes_the_store_and_prints_the_summary(tmp_path, capsys):
    out = tmp_path / "arm.zarr"
    code = main(["workspace", str(TWO_LINK), "--case", "3", "--cone", "shoulder=30",
                 "--grid", "q1_x=-0.6:0.6:3", "--grid", "q4_x=-0.3:0.3:2", "--at", "q3_z=0.1",
                 "--scheduler", "inline", "--chunk", "4", "--out", str(out), "-q"])
    text = capsys.readouterr().out
    assert code == 0, text
    assert "6 poses (grid), chunks of 4" in text
    assert "status: infeasible 4 (66.7 %), optimal 2 (33.3 %)" in text
    assert "wrench-feasible (needed_f_max <= f_max = 1000 N): 6 poses (100.0 %)" in text
    assert "the cones remove 66.7 % of the wrench-feasible workspace" in text
    assert "computed 2 of 2 chunks (6 poses)" in text
    ds = open_workspace(out)
    assert ds.attrs["workspace"]["cones_deg"] == {"shoulder": 30.0}
    ok = ds["status"].values == "optimal"
    need = ds["needed_cone_deg"].values
    angle = ds["interaction_angle_deg"].values[:, 0]
    # where the solver finds no answer the margin says the cone must open past 30 deg; where it does,
    # the answer's angle is within the cone and no smaller than the smallest feasible one
    assert (need[~ok] > 30.0).all() and (need[ok] <= angle[ok] + margins.CONE_TOL_DEG).all()
    assert (angle[ok] <= 30.0 + 1e-6).all() and np.isnan(angle[~ok]).all()
    np.testing.assert_array_equal(ds["q"].values[:, 2], 0.1)


@pytest.mark.parametrize("args, match", [
    (["--grid", "q1_x=0:1"], r"--grid q1_x: expected LO:HI:N, got '0:1'"),
    (["--grid", "q1_x=0:1:3", "--range", "q4_x=0:1"], r"--range applies to --random only"),
    (["--random", "5", "--range", "q1_x=1:0"], r"range q1_x: expected finite LO < HI"),
    (["--grid", "q1_x=0:1:3", "--cone", "shoulder=20"], r"--cone applies to --case 3 only"),
    (["--grid", "q1_x=0:1:3", "--qd", "q7=1"], r"--qd: unknown coordinate 'q7'"),
    (["--grid", "q1_x=0:1:3", "--scheduler", "udp://x"], r"scheduler: expected local, inline or tcp"),
])
def test_command_line_errors_are_one_line(tmp_path, capsys, args, match):
    code = main(["workspace", str(TWO_LINK), *args, "--out", str(tmp_path / "x.zarr"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert re.search(match, err), err
