"""mcdm_pin.plots and ``mcdm-pin plot``: the paper's figure types, runs side by side, gaps where
there is no answer."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, load_trajectory
from mcdm_pin.cli import main
from mcdm_pin.exceptions import ResultsError
from mcdm_pin.plots import FIGURES, infeasible_spans, plot_runs, save_figures



@pytest.fixture(scope="module")
def runs(two_link):
    traj = load_trajectory(two_link, "traj1").subsample(41)
    return [InverseDynamics.for_case(two_link, c).solve_trajectory(traj, progress=False) for c in (1, 3)]


def _line(ax, gid):
    lines = [ln for ln in ax.get_lines() if ln.get_gid() == gid]
    assert len(lines) == 1, f"no single line {gid!r} in {[ln.get_gid() for ln in ax.get_lines()]}"
    return lines[0]


def test_lines_carry_the_results(runs):
    figs = plot_runs(runs, labels=["case 1", "case 3"],
                     figures=["cable_forces", "interaction_angles", "interaction_forces"])
    axes = figs["cable_forces"].axes
    assert len(axes) == 2 and axes[0].get_title() == "case 1" and axes[1].get_title() == "case 3"
    for ax, run in zip(axes, runs):
        x, y = _line(ax, "f:cable2").get_data()
        np.testing.assert_array_equal(x, run.t)
        np.testing.assert_array_equal(y, run.f[:, 1])
    # shared axes: both columns show the same force range
    assert axes[0].get_ylim() == axes[1].get_ylim()
    ang = figs["interaction_angles"].axes
    np.testing.assert_array_equal(_line(ang[1], "angle:shoulder").get_ydata(),
                                  runs[1].interaction_angle_deg[:, 0])
    # rho* of case 3 is drawn in the case-1 column too, and case 1 goes past it
    for ax in ang[:2]:
        assert _line(ax, "rho:shoulder").get_ydata()[0] == pytest.approx(30.0)
    assert np.nanmax(_line(ang[0], "angle:shoulder").get_ydata()) > 40.0
    assert np.nanmax(_line(ang[1], "angle:shoulder").get_ydata()) <= 30.0 + 1e-6
    F = figs["interaction_forces"].axes
    np.testing.assert_allclose(_line(F[0], "F:shoulder").get_ydata(), runs[0].force_magnitude[:, 0])


def test_infeasible_instants_are_gaps_and_marked(runs):
    run = runs[1]
    bad = [5, 6, 7, 30]
    run = type(run)(**{**run.__dict__, "f": run.f.copy(), "status": run.status.astype("U16")})
    run.f[bad] = np.nan
    run.status[bad] = "infeasible"
    t = run.t
    spans = infeasible_spans(t, run.found)
    assert len(spans) == 2
    assert spans[0] == pytest.approx(((t[4] + t[5]) / 2, (t[7] + t[8]) / 2))
    assert spans[1] == pytest.approx(((t[29] + t[30]) / 2, (t[30] + t[31]) / 2))
    ax = plot_runs([run], figures=["cable_forces"])["cable_forces"].axes[0]
    y = _line(ax, "f:cable1").get_ydata()
    assert np.all(np.isnan(y[bad])) and np.all(np.isfinite(np.delete(y, bad)))
    marks = _line(ax, "infeasible-marks")
    np.testing.assert_array_equal(marks.get_xdata(), run.t[bad])
    assert len(ax.patches) == 2  # two shaded spans


def test_files_written(runs, tmp_path):
    paths = save_figures(plot_runs(runs, figures=["summary"]), tmp_path, prefix="traj1_")
    assert [p.name for p in paths] == ["traj1_summary.png", "traj1_summary.svg"]
    from PIL import Image
    img = np.asarray(Image.open(paths[0]).convert("L"))
    assert img.shape[1] > 600 and img.std() > 10  # a drawn figure, not an empty canvas
    assert "<svg" in paths[1].read_text()[:500] and paths[1].stat().st_size > 20_000


def test_cli_plot(runs, tmp_path, capsys):
    npz = []
    for k, run in enumerate(runs):
        npz.append(tmp_path / f"run{k}.npz")
        run.save(npz[-1])
    out = tmp_path / "figs"
    assert main(["plot", *map(str, npz), "--out", str(out), "--figures", "summary,trajectory",
                 "--format", "png"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["summary.png", "trajectory.png"]
    assert "wrote" in capsys.readouterr().out
    assert main(["plot", str(npz[0]), "--out", str(out), "--figures", "nope"]) == 2
    assert "expected one of " + ", ".join(FIGURES) in capsys.readouterr().err
    assert main(["plot", *map(str, npz), "--out", str(out), "--labels", "a"]) == 2


def test_runs_of_different_robots_are_refused(runs):
    other = type(runs[1])(**{**runs[1].__dict__, "joint_names": np.array(["a", "b"])})
    with pytest.raises(ResultsError, match="joint_names .* do not match"):
        plot_runs([runs[0], other])


def test_interaction_angles_only_for_joints_with_a_socket_axis(runs, two_link):
    """The angle from the socket axis means something only for spherical joints: the 2-link arm's
    revolute elbow gets no angle row (it had one, e.g. 92.7 deg for the human elbow)."""
    assert list(runs[0].joint_types) == ["spherical", "revolute"]
    figs = plot_runs(runs, figures=["interaction_angles", "summary"])
    gids = {ln.get_gid() for ax in figs["interaction_angles"].axes for ln in ax.get_lines()}
    assert "angle:shoulder" in gids and "angle:elbow" not in gids
    assert len(figs["interaction_angles"].axes) == 2  # one row (shoulder) x two runs
    # a case-1 run alone (no cone anywhere): the summary shows the spherical joints' angles
    gids = {ln.get_gid() for ax in plot_runs(runs[:1], figures=["summary"])["summary"].axes for ln in ax.get_lines()}
    assert "angle:shoulder" in gids and "angle:elbow" not in gids
    # a robot without spherical joints: no angle figure at all
    only_revolute = type(runs[0])(**{**runs[0].__dict__, "joint_types": np.array(["revolute", "revolute"])})
    assert "interaction_angles" not in plot_runs([only_revolute])
