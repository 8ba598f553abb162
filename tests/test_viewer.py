"""mcdm_pin.viewer: the Meshcat scene of a solved trajectory, its HTML file, the CLI, and real renders
in headless Chromium whose pixels are checked.

The render tests need a Chromium: Debian's ``chromium`` (``.ci/run`` installs it, visibly, before the
tests; the tests themselves never install anything) or ``MCDM_PIN_CHROMIUM``; without one they skip
with the install hint. Chromium runs with no network (every host name resolves to nothing, every
proxied request goes to a closed local port; the page is a local file).
"""

from __future__ import annotations

import base64
import json
import re

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, load_trajectory
from mcdm_pin.cli import main
from mcdm_pin.exceptions import ResultsError
from mcdm_pin.viewer import (CABLE_MAP, CONE_OK_RGB, CONE_OUT_RGB, build_scene, empty_scene, mute,
                             nice_ceil, screenshot, tension_rgb)
from mcdm_pin.viewer.camera import FILL, FOV_DEG, camera_basis

from .conftest import REPO, TWO_LINK

HUMAN = REPO / "robots" / "human_arm.yaml"


@pytest.fixture(scope="module")
def runs(two_link):
    traj = load_trajectory(two_link, "traj1")
    return {case: InverseDynamics.for_case(two_link, case).solve_trajectory(traj, progress=False)
            for case in (1, 3)}


def _tracks(scene, path):
    return {tr.name: tr for tr in scene.tracks[path]}


def expected_rgb(f, fmax):
    """The cable colour scale written out independently of the viewer: the documented colours at equal
    steps of [0, fmax], linear in between, clipped at both ends; no answer (NaN) grey."""
    f = np.atleast_1d(np.asarray(f, dtype=float))
    stops = np.linspace(0.0, fmax, len(CABLE_MAP))
    x = np.clip(np.where(np.isfinite(f), f, 0.0), 0.0, fmax)
    out = np.stack([np.interp(x, stops, CABLE_MAP[:, c]) for c in range(3)], axis=-1)
    out[~np.isfinite(f)] = 0.55
    return out


def test_colour_scale_is_fixed_and_documented():
    # a finer "nice" top: the 2-link arm's 53.8 N peak is drawn on 0..60 N, not 0..100 N
    assert nice_ceil(53.8) == 60.0 and nice_ceil(125.2) == 150.0 and nice_ceil(158.3) == 200.0
    assert nice_ceil(0.3) == 0.3 and nice_ceil(401.0) == 500.0 and nice_ceil(10.0) == 10.0
    for x in np.geomspace(1e-3, 1e5, 200):
        assert x <= nice_ceil(x) <= 1.34 * x  # at most a third above the peak
    rgb = tension_rgb([0.0, 50.0, 100.0, 250.0, np.nan], 100.0)
    np.testing.assert_allclose(rgb, expected_rgb([0.0, 50.0, 100.0, 250.0, np.nan], 100.0), atol=1e-12)
    np.testing.assert_allclose(rgb[0], CABLE_MAP[0])
    np.testing.assert_allclose(rgb[2], CABLE_MAP[-1])
    np.testing.assert_allclose(rgb[3], CABLE_MAP[-1])  # above the scale: the top colour
    assert np.allclose(rgb[4], rgb[4][0])  # no answer: grey
    # a cable at its minimum force is a clear blue, not turbo's near-black: far from the muted steel and
    # greys of primitive links and from the ghosted (80 % grey) skins, at any lighting (0.3..1.1 x)
    assert CABLE_MAP[0].max() > 0.75
    links = [mute(rgb) for rgb in [(0.35, 0.45, 0.6), (0.6, 0.6, 0.6), (0.2, 0.2, 0.2), (0.9, 0.9, 0.9)]]
    links += [mute(rgb, 0.8) for rgb in [(0.0, 0.0, 0.8), (0.8, 0.0, 0.0), (0.0, 0.8, 0.0)]]
    for link in links:
        assert min(np.linalg.norm(s * link - CABLE_MAP[0]) for s in np.linspace(0.3, 1.1, 17)) > 0.2


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
                                   expected_rgb(run.f[:, two_link.cable_names.index(c.name)], scene.fmax),
                                   atol=1e-12)
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
    # every arrow says which joint it belongs to: a label sprite that follows the joint point
    for joint in two_link.joint_names:
        label = [c for c in scene.commands if c["type"] == "set_object" and c["path"] ==
                 f"/meshcat/mcdm/labels/{joint}/label"]
        assert len(label) == 1 and label[0]["object"]["object"]["type"] == "Sprite"
        assert "visible" in _tracks(scene, f"/meshcat/mcdm/labels/{joint}")
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
    label = _tracks(scene, "/meshcat/mcdm/labels/shoulder")["visible"].values
    np.testing.assert_array_equal(label, visible)
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
    # the files the other way round are told apart by their content; a URDF is named for what it is
    assert main(["view", str(npz), "--results", str(TWO_LINK), "--html", str(tmp_path / "w.html")]) == 0
    assert main(["view", str(REPO / "urdf" / "two_link_sr.urdf"), "--results", str(npz), "--no-wait"]) == 2
    err = capsys.readouterr().err
    assert "is a URDF" in err and "robots/two_link_sr.yaml" in err


def test_links_are_drawn_from_pinocchios_visual_model(two_link, runs):
    """The URDF's visuals come from pin.buildGeomFromUrdf (no XML read by hand): link1's 0.2 m cylinder
    of radius 12 mm, centred 0.1 m up its frame, in its URDF colour muted."""
    scene = build_scene(two_link, runs[1])
    objects = {c["path"]: c["object"] for c in scene.commands if c["type"] == "set_object"}
    geo = objects["/meshcat/mcdm/links/link1/visual0"]["geometries"][0]
    assert geo["type"] == "CylinderGeometry" and geo["height"] == pytest.approx(0.2)
    assert geo["radiusTop"] == pytest.approx(0.012)
    pose = [c["matrix"] for c in scene.commands if c["type"] == "set_transform"
            and c["path"] == "/meshcat/mcdm/links/link1/visual0"][0]
    assert np.reshape(pose, (4, 4)).T[:3, 3] == pytest.approx([0.0, 0.0, 0.1])
    # the massless links inside the Euler-triple shoulder get no simple shape
    assert not any(p.startswith("/meshcat/mcdm/bodies/q1_x/bone") for p in objects)
    import mcdm_pin.viewer as viewer
    from pathlib import Path
    for module in Path(viewer.__file__).parent.glob("*.py"):
        text = module.read_text()
        assert "xml.etree" not in text and "ElementTree" not in text
        assert len(text.splitlines()) < 400, f"{module.name}: one job per module"


def test_the_human_stands_upright_with_muted_translucent_skin():
    """example-robot-data's human is built y-up: the scene turns its world so that gravity (-y) points
    down the screen; its bright skin meshes are drawn muted and translucent so that the muscles inside
    show."""
    robot = Robot.load(HUMAN)
    run = InverseDynamics.for_case(robot, 1).solve_trajectory(load_trajectory(robot, "reach_forward")
                                                              .subsample(5), progress=False)
    scene = build_scene(robot, run)
    np.testing.assert_allclose(scene.up @ np.array([0.0, -9.81, 0.0]), [0.0, 0.0, -9.81], atol=1e-12)
    meshes = [c["object"] for c in scene.commands if c["type"] == "set_object"
              and c["object"]["object"]["type"] == "Mesh"
              and c["object"]["geometries"][0]["type"] == "BufferGeometry"]
    assert len(meshes) >= 20  # the body's meshes, loaded by Pinocchio (coal) from the installed package
    for m in meshes:
        mat = m["materials"][0]
        rgb = np.array([(mat["color"] >> s) & 255 for s in (16, 8, 0)]) / 255
        assert mat["opacity"] == pytest.approx(0.3) and np.ptp(rgb) < 0.2  # translucent, near grey


def test_camera_frames_every_point():
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(200, 3)) * [0.3, 0.1, 0.5] + [0.2, -0.1, 0.05]
    for direction in ([0.85, -0.45, 0.38], [0.0, 1.0, 0.2], [-1.0, 0.3, 0.6]):
        target, cam = camera_basis(direction)[0], None
        from mcdm_pin.viewer.camera import camera_position
        target, cam = camera_position(pts, direction, aspect=1.25)
        u, right, up = camera_basis(cam)
        p = pts - target - cam
        depth = p @ -u
        x = (p @ right) / depth / (np.tan(np.radians(FOV_DEG) / 2) * 1.25)
        y = (p @ up) / depth / np.tan(np.radians(FOV_DEG) / 2)
        assert max(np.abs(x).max(), np.abs(y).max()) == pytest.approx(FILL, abs=1e-6)  # tight ...
        assert abs(x.max() + x.min()) < 0.02 and abs(y.max() + y.min()) < 0.02  # ... and centred


# ------------------------------------------------------------------------------ headless chromium
def _img(path):
    from PIL import Image
    return np.asarray(Image.open(path).convert("RGB"), dtype=float) / 255.0


def _near(img, rgb, tol=0.06):
    return np.all(np.abs(img - np.asarray(rgb)) < tol, axis=2)


def _render(scene, tmp_path, name):
    """Screenshots of the scene and of its environment alone (same camera), and the mask of the
    pixels the robot changes."""
    png = screenshot(scene.write_html(tmp_path / f"{name}.html"), tmp_path / f"{name}.png")
    png0 = screenshot(empty_scene(scene).write_html(tmp_path / f"{name}_empty.html"), tmp_path / f"{name}_empty.png")
    img, ref = _img(png), _img(png0)
    assert img.shape == ref.shape == (800, 1000, 3)
    return img, ref, np.any(np.abs(img - ref) > 0.1, axis=2)


def _bbox_share(mask):
    """(height, width) of the robot's pixel bounding box as shares of the image's (rows and columns
    with at least 3 robot pixels)."""
    rows, cols = np.flatnonzero(mask.sum(axis=1) >= 3), np.flatnonzero(mask.sum(axis=0) >= 3)
    return (rows[-1] - rows[0] + 1) / mask.shape[0], (cols[-1] - cols[0] + 1) / mask.shape[1]


def _stray_lines(img, mask):
    """Pixels of the upper-left block (300 x 330) that are not the robot's and differ by more than 0.05
    from their row's background (Meshcat's background is a vertical gradient: every row is uniform).
    The band of grid lines of the old viewer gave 5552 such pixels on the 2-link arm, 0 now."""
    block, robot = img[:300, :330], mask[:300, :330]
    dev = np.abs(block - np.median(block, axis=1, keepdims=True)).max(axis=2)
    return int((dev[~robot] > 0.05).sum())


def _pixel(scene, p_world, shape=(800, 1000)):
    """(row, col) of a robot-world point in the screenshot (Meshcat's camera: vertical field of view 75
    deg, looking at the display origin from ``scene.camera``, z up)."""
    d = scene.up @ np.asarray(p_world, float) - scene.center - scene.camera
    u, right, up = camera_basis(scene.camera)
    depth = d @ -u
    t = np.tan(np.radians(FOV_DEG) / 2)
    x, y = (d @ right) / depth / (t * shape[1] / shape[0]), (d @ up) / depth / t
    return int(round((1 - y) / 2 * shape[0] - 0.5)), int(round((1 + x) / 2 * shape[1] - 0.5))


def test_chromium_two_link_framed_no_stray_grid_and_minimum_force_cables_stand_out(chromium, two_link, runs,
                                                                                   tmp_path):
    run = runs[1]
    k = int(np.argmin(np.abs(run.t - 0.2)))  # cables 2 and 6 pull hard, the others sit at 1 mN
    scene = build_scene(two_link, run, start_time=float(run.t[k]), legend=False)
    img, ref, mask = _render(scene, tmp_path, "two_link")
    assert ref.std() > 0.01  # the environment is not blank (gradient, floor grid)
    # framed: measured 0.82 of the height and 0.61 of the width (the old camera: 0.62 and 0.44)
    h, w = _bbox_share(mask)
    assert max(h, w) > 0.75 and h * w > 0.4, (h, w)
    assert _stray_lines(img, mask) == 0
    # cables are unlit: their pixels have exactly the scale's colours; at this instant at least two
    # clearly different colours are seen on screen (and not in the empty scene)
    seen = []
    for rgb in expected_rgb(run.f[k], scene.fmax):
        n = int(np.sum(_near(img, rgb) & ~_near(ref, rgb)))
        if n >= 15 and all(np.abs(rgb - s).max() > 0.25 for s in seen):
            seen.append(rgb)
    assert len(seen) >= 2, f"cable colours on screen: {seen}"
    # minimum-force cables against the links: project points along the cables at 1 mN and along
    # both links into the picture and compare the colours found there
    from mcdm_pin import compute_terms
    terms = compute_terms(two_link, run.q[k])
    low = [i for i in range(two_link.m) if run.f[k, i] < 0.01]
    cable_px = []
    for i in low:
        a, b = (terms.points[p] for p in (two_link.cables.seg_a[i], two_link.cables.seg_b[i]))
        for s in np.linspace(0.1, 0.9, 25):
            r, c = _pixel(scene, a + s * (b - a))
            cable_px.append(img[r, c])
    cable_px = np.array(cable_px)
    on_cable = np.linalg.norm(cable_px - CABLE_MAP[0], axis=1) < 0.1
    assert on_cable.sum() >= 20, on_cable.sum()  # found where the camera model says they are
    link_px = []
    for jid in (3, 4):  # link1 and link2: 0.2 m along each joint frame's z
        from mcdm_pin.viewer.scene import kinematics
        T = kinematics(two_link, run).joint_T[k, jid]
        for s in np.linspace(0.05, 0.18, 12):
            r, c = _pixel(scene, T[:3, :3] @ [0.0, 0.0, s] + T[:3, 3])
            link_px.append(img[r, c])
    link = np.median(np.array(link_px), axis=0)
    cable = np.median(cable_px[on_cable], axis=0)
    # distinct in colour (chroma = max - min channel): a saturated blue cable on a grey link, measured
    # 0.53 against 0.07; the old viewer's near-black violet on steel measured 0.16 against 0.18
    assert np.ptp(cable) - np.ptp(link) > 0.3, (cable, link)
    assert np.linalg.norm(link - cable) > 0.3  # measured 0.35 (old: 0.31)


def test_chromium_human_arm_upright_and_framed(chromium, tmp_path):
    robot = Robot.load(HUMAN)
    run = InverseDynamics.for_case(robot, 1).solve_trajectory(load_trajectory(robot, "reach_forward")
                                                              .subsample(16), progress=False)
    scene = build_scene(robot, run, start_time=1.0, legend=False)
    img, ref, mask = _render(scene, tmp_path, "human")
    h, w = _bbox_share(mask)
    # upright (the old viewer drew it lying on its side: 0.58 high, 0.91 wide) and framed
    assert h > 0.8 and h > 1.3 * w, (h, w)
    assert _stray_lines(img, mask) == 0
    # the muscles are on screen: pixels of the cable scale's colours, unlit, not in the empty scene
    cable_colors = expected_rgb(run.f[run.t == 1.0][0], scene.fmax)
    n = sum(int(np.sum(_near(img, rgb, 0.04) & ~_near(ref, rgb, 0.04))) for rgb in np.unique(cable_colors, axis=0))
    assert n > 300, n


def test_wrapped_routes_are_drawn_on_their_surfaces_with_the_routes_length(tmp_path, monkeypatch):
    """MyoSuite's arm (62 cylinder and 35 sphere wraps): at 12 random states (joint ranges, couplings
    kept) each drawn cable, straight pieces plus every engaged wrap's great-circle arc or helix
    sampled by the rule of mcdm_pin/viewer/arcs.py, is as long as MuJoCo's ten_length to 1e-6 relative
    (measured 9e-7 at most; never longer), every vertex of an arc lies on its surface, and drawing the
    chords instead (one piece per wrap) misses by up to 14 % (measured)."""
    mujoco = pytest.importorskip("mujoco")
    import pinocchio as pin

    from mcdm_pin.viewer.arcs import _sample, _surface_path, route_polylines
    from mcdm_pin.viewer.scene import kinematics

    monkeypatch.chdir(tmp_path)  # MuJoCo writes MUJOCO_LOG.TXT where it runs
    robot = Robot.load(REPO / "robots" / "myosuite" / "myoarm.yaml")
    mj = mujoco.MjModel.from_xml_path(str(robot.sidecar.mjcf_path))
    d = mujoco.MjData(mj)
    acts = [mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_ACTUATOR, n) for n in robot.cable_names]
    tendon = np.array([int(mj.actuator_trnid[a, 0]) for a in acts])
    rng = np.random.default_rng(7)
    conf, ref = [], []
    for _ in range(12):
        qpos = mj.qpos0.copy()
        for j in range(mj.njnt):  # hinges and slides only in this model
            lo, hi = mj.jnt_range[j] if mj.jnt_limited[j] else (-1.0, 1.0)
            qpos[mj.jnt_qposadr[j]] = rng.uniform(lo, hi)
        q, _, _ = robot.couplings.fill(robot.source.maps.to_pin_q(qpos))
        d.qpos[:] = robot.source.maps.to_mj_qpos(q)
        mujoco.mj_kinematics(mj, d)
        mujoco.mj_comPos(mj, d)
        mujoco.mj_tendon(mj, d)
        conf.append(q)
        ref.append(d.ten_length[tendon].copy())
    conf, ref = np.array(conf), np.array(ref)

    def drawn(tol):
        seg, cable, scale = route_polylines(robot, conf, tol)
        out = np.zeros_like(ref)
        for k in range(len(conf)):
            np.add.at(out[k], cable, scale[k] * np.linalg.norm(seg[k, :, 1] - seg[k, :, 0], axis=1))
        return out, seg, cable

    length, seg, cable = drawn(1e-6)
    rel = (ref - length) / ref
    assert rel.max() <= 1e-6 and rel.min() >= -1e-12  # a polyline on the surface is never longer
    chords, *_ = drawn(1e3)  # the rule then gives one piece per wrap: the chord
    assert ((ref - chords) / ref).max() > 1e-2
    # the scene's cables are these polylines
    run = type("Run", (), {"configuration": conf, "q": None})()
    kin = kinematics(robot, run)
    assert np.array_equal(kin.segments, seg) and np.array_equal(kin.seg_cable, cable)
    coarse = kinematics(robot, run, arc_tol=1e-3).segments.shape[1]  # view --arc-tol: a smaller file
    assert robot.m < coarse < seg.shape[1]
    # every vertex on its surface: the sphere's centre at distance r; the cylinder's axis at distance r,
    # its height linear in the angle (a helix)
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, conf[0])
    oM = np.array([data.oMi[j].homogeneous for j in range(robot.model.njoints)])
    X = lambda j, p: oM[j, :3, :3] @ p + oM[j, :3, 3]  # noqa: E731
    c, checked = robot.cables, {"sphere": 0, "cylinder": 0}
    for wr in c.wraps:
        path = _surface_path(wr, oM, X(c.point_joint[wr.a], c.point_local[wr.a]),
                             X(c.point_joint[wr.b], c.point_local[wr.b]))
        if path is None:
            continue
        local = (_sample(path, 16) - path.M[:3, 3]) @ path.M[:3, :3]
        radial = local[:, :2] if wr.kind == "cylinder" else local
        assert np.allclose(np.linalg.norm(radial, axis=1), wr.radius, rtol=1e-12, atol=0)
        if wr.kind == "cylinder":
            angle = np.unwrap(np.arctan2(local[:, 1], local[:, 0]))
            assert np.allclose(np.diff(local[:, 2]) * (angle[-1] - angle[0]), np.diff(angle) * path.rise,
                               atol=1e-14)
        checked[wr.kind] += 1
    assert min(checked.values()) >= 3
