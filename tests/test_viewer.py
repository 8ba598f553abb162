"""mcdm_pin.viewer: the Meshcat scene of a solved trajectory, its HTML file, the CLI, and a real render
in headless Chromium.

The render test needs Debian's ``chromium``: the ``chromium`` fixture (tests/conftest.py) installs it
with ``apt-get install chromium`` when it is missing (CI runs as root); ``MCDM_PIN_CHROMIUM`` may name
another binary. It starts Chromium
with no network (every host name resolves to nothing, every proxied request goes to a closed local
port; the page is a local file), takes a screenshot and compares it with one of the same viewer
environment with nothing in it.
"""

from __future__ import annotations

import base64
import json
import re

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, load_trajectory
from mcdm_pin.cli import main
from mcdm_pin.exceptions import ResultsError
from mcdm_pin.viewer import (CONE_OK_RGB, CONE_OUT_RGB, TURBO, build_scene, empty_scene,
                             nice_ceil, screenshot, tension_rgb)

from .conftest import TWO_LINK


@pytest.fixture(scope="module")
def runs(two_link):
    traj = load_trajectory(two_link, "traj1")
    return {case: InverseDynamics.for_case(two_link, case).solve_trajectory(traj, progress=False)
            for case in (1, 3)}


def _tracks(scene, path):
    return {tr.name: tr for tr in scene.tracks[path]}


def test_colour_scale_is_fixed_and_documented():
    assert nice_ceil(53.7) == 100.0 and nice_ceil(158.3) == 200.0 and nice_ceil(0.3) == 0.5
    rgb = tension_rgb([0.0, 50.0, 100.0, 250.0, np.nan], 100.0)
    np.testing.assert_allclose(rgb[0], TURBO[0])
    np.testing.assert_allclose(rgb[2], TURBO[-1])
    np.testing.assert_allclose(rgb[3], TURBO[-1])  # above the scale: the top colour
    np.testing.assert_allclose(rgb[1], TURBO[5])
    assert np.allclose(rgb[4], rgb[4][0])  # no answer: grey


def test_scene_animates_every_cable_segment_by_tension(two_link, runs):
    run = runs[1]
    scene = build_scene(two_link, run)
    assert scene.fmax == nice_ceil(np.nanmax(run.f))
    objects = {c["path"] for c in scene.commands if c["type"] == "set_object"}
    for c in two_link.cables:  # one segment each
        path = f"/meshcat/mcdm/cables/{c.name}/s0"
        assert path in objects
        tr = _tracks(scene, path)
        np.testing.assert_allclose(tr["body.material.color"].values,
                                   tension_rgb(run.f[:, two_link.cable_names.index(c.name)], scene.fmax))
        # the cylinder spans the attachment points: its length is the cable length
        lengths = tr["scale"].values[:, 1]
        k = 37
        from mcdm_pin import compute_terms
        terms = compute_terms(two_link, run.q[k])
        assert lengths[k] == pytest.approx(terms.lengths[two_link.cable_names.index(c.name)], rel=1e-12)
    # the interaction-force arrows: shaft + head length = |F| * arrow_scale
    sh = _tracks(scene, "/meshcat/mcdm/forces/shoulder/shaft")["scale"].values[:, 1]
    hd = _tracks(scene, "/meshcat/mcdm/forces/shoulder/head")["scale"].values[:, 0]
    head = 0.065 * scene.extent
    np.testing.assert_allclose(sh + hd * head, run.force_magnitude[:, 0] * scene.arrow_scale, atol=1e-6)
    # keys are the trajectory's time
    assert [k["time"] for k in tr["position"].lower()["keys"]] == pytest.approx(run.t.tolist())


def test_cone_turns_red_outside(two_link, runs):
    path = "/meshcat/mcdm/cones/shoulder/cone"
    for case, run in runs.items():
        colors = _tracks(build_scene(two_link, run), path)["body.material.color"].values
        out = run.interaction_angle_deg[:, 0] > 30.0 + 1e-6
        np.testing.assert_allclose(colors[out], np.tile(CONE_OUT_RGB, (out.sum(), 1)))
        np.testing.assert_allclose(colors[~out], np.tile(CONE_OK_RGB, ((~out).sum(), 1)))
        # case 1 ignores the cone (and leaves it); case 3 keeps the force inside
        assert out.any() if case == 1 else not out.any()
    assert "/meshcat/mcdm/cones/elbow/cone" not in build_scene(two_link, runs[1]).tracks


def test_infeasible_instants_are_grey_and_arrows_hidden(two_link, runs):
    run = runs[3]
    bad = np.array([10, 11, 12])
    run = type(run)(**{**run.__dict__, "f": run.f.copy(), "status": run.status.astype("U16"),
                       "interaction_wrench": run.interaction_wrench.copy(),
                       "interaction_angle_deg": run.interaction_angle_deg.copy()})
    run.f[bad] = np.nan
    run.status[bad] = "infeasible"
    run.interaction_wrench[bad] = np.nan
    run.interaction_angle_deg[bad] = np.nan
    scene = build_scene(two_link, run)
    colors = _tracks(scene, "/meshcat/mcdm/cables/cable1/s0")["body.material.color"].values
    assert np.allclose(colors[bad], 0.55)
    visible = _tracks(scene, "/meshcat/mcdm/forces/shoulder")["visible"].values
    assert not visible[bad].any() and visible[20]
    assert '"infeasible"' in scene.html()


def test_results_of_another_robot_are_refused(two_link, runs, tmp_path):
    run = runs[1]
    other = type(run)(**{**run.__dict__, "cable_names": np.array([f"c{i}" for i in range(8)])})
    with pytest.raises(ResultsError, match=r"other\.npz: cable_names .* do not match robot 'two_link_sr'"):
        build_scene(two_link, other, source="other.npz")
    short = type(run)(**{**run.__dict__, "q": run.q[:, :3]})
    with pytest.raises(ResultsError, match=r"q has shape \(101, 3\); expected \(101, 4\)"):
        build_scene(two_link, short)
    bad = tmp_path / "other.npz"
    other.save(bad)
    assert main(["view", str(TWO_LINK), "--results", str(bad), "--html", str(tmp_path / "x.html")]) == 2


def test_html_is_self_contained(two_link, runs, tmp_path):
    path = build_scene(two_link, runs[3]).write_html(tmp_path / "run.html")
    text = path.read_text()
    assert not re.search(r"<(script|link|img)[^>]+(src|href)=", text)  # nothing loaded from outside
    blobs = json.loads(re.search(r"var MCDM_COMMANDS = (\[.*?\]);", text).group(1))
    import umsgpack
    cmds = [umsgpack.unpackb(base64.b64decode(b)) for b in blobs]
    assert cmds[-1]["type"] == "set_animation"  # replayed after every object it binds to
    assert sum(c["type"] == "set_object" for c in cmds) > 8


def test_cli_view_and_solve_html(tmp_path, capsys):
    npz, html = tmp_path / "run.npz", tmp_path / "solve.html"
    assert main(["solve", str(TWO_LINK), "-t", "traj1", "--case", "3", "--samples", "21", "-q",
                 "--out", str(npz), "--html", str(html)]) == 0
    assert html.stat().st_size > 100_000 and "wrote" in capsys.readouterr().out
    assert main(["view", str(TWO_LINK), "--results", str(npz), "--no-wait"]) == 0
    assert (tmp_path / "run.html").is_file()  # default name: beside the results
    assert main(["view", str(TWO_LINK), "--results", str(npz), "--html", str(tmp_path / "v.txt")]) == 2
    assert main(["view", str(TWO_LINK), "--results", str(npz), "--no-wait", "--time", "5"]) == 2
    assert "outside the trajectory" in capsys.readouterr().err


# ------------------------------------------------------------------------------ headless chromium
def _img(path):
    from PIL import Image
    return np.asarray(Image.open(path).convert("RGB"), dtype=float) / 255.0


def _near(img, rgb, tol=0.06):
    return np.all(np.abs(img - np.asarray(rgb)) < tol, axis=2)


def test_chromium_renders_the_scene_with_coloured_cables(chromium, two_link, runs, tmp_path):
    run = runs[1]
    k = int(np.argmin(np.abs(run.t - 0.2)))  # cables 2 and 6 pull hard, the others barely
    scene = build_scene(two_link, run, start_time=float(run.t[k]), legend=False)
    empty = empty_scene(scene.center, scene.extent)
    png = screenshot(scene.write_html(tmp_path / "scene.html"), tmp_path / "scene.png")
    png0 = screenshot(empty.write_html(tmp_path / "empty.html"), tmp_path / "empty.png")
    img, ref = _img(png), _img(png0)
    assert img.shape == ref.shape == (800, 1000, 3)
    # the empty Meshcat scene is not blank (gradient, grid, axes) ...
    assert ref.std() > 0.01
    # ... and the robot changes a good part of it
    changed = np.any(np.abs(img - ref) > 0.1, axis=2)
    assert changed.mean() > 0.03, f"only {changed.mean():.4f} of the pixels differ from the empty scene"
    # cables are unlit: their pixels have exactly the scale's colours; at this instant the scale gives
    # at least two clearly different colours, each seen on screen (and not in the empty scene)
    colors = tension_rgb(run.f[k], scene.fmax)
    seen = []
    for rgb in colors:
        n = int(np.sum(_near(img, rgb) & ~_near(ref, rgb)))
        if n >= 15 and all(np.abs(rgb - s).max() > 0.25 for s in seen):
            seen.append(rgb)
    assert len(seen) >= 2, f"cable colours on screen: {seen}"
