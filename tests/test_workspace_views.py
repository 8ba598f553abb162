"""Seeing a workspace: the heat maps of a 2-D grid (mcdm-pin plot) and the point cloud (mcdm-pin view)."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin.cli import main
from mcdm_pin.plots import PlotError, figure_workspace
from mcdm_pin.workspace import Grid, RandomPoses, Setup, WorkspaceError, as_grid, compute_workspace
from mcdm_pin.workspace.cloud import cloud_scene, frame_positions, margin_colors

from .conftest import TWO_LINK


@pytest.fixture(scope="module")
def grid_store(tmp_path_factory, two_link):
    path = tmp_path_factory.mktemp("views") / "arm.zarr"
    poses = Grid(two_link, {"q1_x": (-0.6, 0.6, 3), "q4_x": (-0.3, 0.3, 4)}, at={"q3_z": 0.1})
    compute_workspace(two_link, poses, path, Setup(case=3, cones={"shoulder": 30.0}), chunk=6,
                      scheduler="inline")
    return path


@pytest.fixture(scope="module")
def grid_ds(grid_store):
    from mcdm_pin.workspace import open_workspace

    return open_workspace(grid_store)


def test_heat_maps_have_units_colour_bars_and_the_limits(grid_ds):
    fig = figure_workspace(as_grid(grid_ds))
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in panels] == [
        "status", "needed_f_max (line: 1000; hatched: none)", "needed_cone_deg (line: 30; hatched: none)"]
    assert panels[0].get_xlabel() == "q4_x, rad" and panels[0].get_ylabel() == "q1_x, rad"
    bars = [ax.get_ylabel() for ax in fig.axes if not ax.get_title()]
    assert bars == ["smallest common f_max, N", "smallest cone half-angle, deg"]
    legend = [t.get_text() for t in panels[0].get_legend().get_texts()]
    status = grid_ds["status"].values
    n_ok = int((status == "optimal").sum())
    assert 0 < n_ok < 12 and legend == [f"optimal ({n_ok})", f"infeasible ({12 - n_ok})"]
    # some poses need more than the 30 deg cone, some less: the line between them is drawn
    need = grid_ds["needed_cone_deg"].values
    assert (need > 30).any() and (need < 30).any()
    lines = [c for c in panels[2].collections if not getattr(c, "filled", True)]
    assert [list(c.levels) for c in lines] == [[30.0]]


def test_plot_command_writes_the_heat_maps_of_a_store(grid_store, tmp_path, capsys):
    assert main(["plot", str(grid_store), "--out", str(tmp_path), "--format", "png"]) == 0
    png = tmp_path / "arm.png"
    assert png.is_file() and png.stat().st_size > 20_000
    assert f"wrote {png}" in capsys.readouterr().out


def test_heat_maps_need_a_two_axis_grid(two_link, tmp_path):
    ds = compute_workspace(two_link, RandomPoses(two_link, 4), tmp_path / "r.zarr", Setup(case=1),
                           scheduler="inline").open()
    with pytest.raises(WorkspaceError, match="poses are random, not a grid"):
        as_grid(ds)
    line = compute_workspace(two_link, Grid(two_link, {"q1_x": (0, 1, 3)}), tmp_path / "g.zarr",
                             Setup(case=1, margins=False), scheduler="inline").open()
    with pytest.raises(PlotError, match="exactly two axes"):
        figure_workspace(as_grid(line))


def test_point_cloud_places_each_pose_at_the_frame_and_colours_it_by_margin(grid_ds, two_link):
    q = grid_ds["q"].values
    p = frame_positions(two_link, q, "link2")
    # link2's frame is the elbow, 0.2 m up link 1, which turns about x by q1_x (q2_y = 0, q3_z = 0.1)
    np.testing.assert_allclose(np.linalg.norm(p, axis=1), 0.2, atol=1e-12)
    np.testing.assert_allclose(p[:, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.arctan2(-p[:, 1], p[:, 2]), q[:, 0], atol=1e-12)
    rgb = margin_colors(np.array([0.0, 15.0, 30.0, 31.0, np.inf, np.nan]), 30.0)
    assert np.allclose(rgb[3], (1, 0, 0)) and np.allclose(rgb[4], rgb[5]) and np.allclose(rgb[4], 0.55)
    assert rgb[0][2] > rgb[0][0] and rgb[2][0] > rgb[2][2]  # blue at 0, red at the limit
    scene = cloud_scene(two_link, grid_ds, "link2", color_by="needed_cone_deg")
    cloud = [c for c in scene.commands if c.get("path") == "/meshcat/mcdm/workspace"]
    assert len(cloud) == 1 and cloud[0]["object"]["object"]["type"] == "Points"
    assert "12 poses of 'link2', coloured by needed_cone_deg (0 .. 30" in scene.info[-1]
    assert "<html" in scene.html()[:200].lower()


def test_view_command_writes_the_cloud(grid_store, tmp_path, capsys):
    store = grid_store
    html = tmp_path / "cloud.html"
    assert main(["view", str(TWO_LINK), "--workspace", str(store), "--frame", "link2",
                 "--html", str(html)]) == 0
    assert html.stat().st_size > 100_000
    assert main(["view", str(TWO_LINK), "--workspace", str(store), "--html", str(html)]) == 2
    assert "--workspace needs --frame LINK" in capsys.readouterr().err
