"""Spatial-tendon paths (mcdm_pin.model.wrapping) against MuJoCo 4.0 and against plain geometry.

MuJoCo is the reference for lengths (``ten_length``), the path points (``wrap_xpos``, ``wrap_obj``)
and the Jacobian (``ten_J``, rebuilt here from our straight segments with MuJoCo's own point Jacobians
``mj_jac`` of each end on its element's body). Models: small MJCF strings written to exercise each
case, and MyoSuite's elbow, finger (pulleys) and right arm (Apache-2.0; arm lineage MoBL, Holzbaur
et al. 2005).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mcdm_pin.exceptions import ModelError
from mcdm_pin.model.wrapping import tendon_path, wrap_cylinder, wrap_sphere

mujoco = pytest.importorskip("mujoco")

N_STATES = 60
N_STATES_MYO = 50


@pytest.fixture(autouse=True)
def _tmp_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # MuJoCo writes MUJOCO_LOG.TXT into the working folder on warnings


# ------------------------------------------------------------------ one wrap, plain geometry

def _angle(a, b):
    return math.acos(np.clip(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)), -1, 1))


def test_sphere_tangents_are_tangent_and_arc_is_great_circle():
    r = 0.7
    p0, p1 = np.array([-2.0, -0.5, 0.3]), np.array([1.5, -0.4, -0.2])
    w = wrap_sphere(p0, p1, r)
    assert w.engaged
    for p, t in ((p0, w.t0), (p1, w.t1)):
        assert np.linalg.norm(t) == pytest.approx(r, abs=1e-14)
        assert t @ (p - t) == pytest.approx(0.0, abs=1e-14)          # tangent
        assert np.cross(p0, p1) @ t == pytest.approx(0.0, abs=1e-14)  # in the plane centre-p0-p1
    assert w.arc == pytest.approx(r * _angle(w.t0, w.t1), rel=1e-14)
    assert np.linalg.norm(w.t0 - p0) < np.linalg.norm(w.t1 - p0)


def test_cylinder_path_unrolls_to_a_straight_line():
    r = 0.3
    p0, p1 = np.array([-1.0, -0.1, 0.2]), np.array([0.8, -0.2, 1.1])
    w = wrap_cylinder(p0, p1, r)
    assert w.engaged
    for p, t in ((p0, w.t0), (p1, w.t1)):
        assert math.hypot(t[0], t[1]) == pytest.approx(r, abs=1e-14)
        assert t[:2] @ (p[:2] - t[:2]) == pytest.approx(0.0, abs=1e-14)
    a = r * _angle(w.t0[:2], w.t1[:2])
    l0, l1 = np.linalg.norm(p0[:2] - w.t0[:2]), np.linalg.norm(p1[:2] - w.t1[:2])
    assert w.arc == pytest.approx(math.hypot(a, w.t1[2] - w.t0[2]), rel=1e-14)
    total = np.linalg.norm(w.t0 - p0) + w.arc + np.linalg.norm(p1 - w.t1)
    assert total == pytest.approx(math.hypot(l0 + a + l1, p1[2] - p0[2]), rel=1e-14)  # a helix


def test_no_wrap_conventions_and_side_points():
    r = 1.0
    p0, p1 = np.array([-2.0, 1.5, 0.0]), np.array([2.0, 1.5, 0.0])   # the line misses the sphere
    assert not wrap_sphere(p0, p1, r).engaged
    assert not wrap_sphere(p0, p1, r, side=[0.0, 3.0, 0.0]).engaged  # p0 -> side -> p1 passes above
    forced = wrap_sphere(p0, p1, r, side=[0.0, -3.0, 0.0])           # ... passes below: wraps below
    assert forced.engaged and forced.t0[1] < 0 and forced.t1[1] < 0
    assert not wrap_sphere([0.5, 0.0, 0.0], p1, r).engaged            # an end inside
    assert not wrap_sphere([0.0, 0.0, 0.0], p1, r).engaged            # an end at the centre
    through = wrap_sphere([-2.0, -0.1, 0.0], [2.0, -0.1, 0.0], r)      # the line crosses: wraps
    assert through.engaged and through.t0[1] < 0                        # the shorter way round
    other = wrap_sphere([-2.0, -0.1, 0.0], [2.0, -0.1, 0.0], r, side=[0.0, 5.0, 0.0])
    assert other.engaged and other.t0[1] > 0 and other.arc > through.arc
    # a cylinder's end inside the infinite cylinder does not wrap, however far along the axis
    assert not wrap_cylinder([0.5, 0.0, 10.0], [2.0, -0.1, 0.0], r).engaged


def _turn(a, b):
    return math.atan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1])


def test_side_point_sets_the_winding_and_the_path_snaps_on_the_opposite_ray():
    r = 1.0
    side = np.array([0.0, -3.0, 0.7])  # its direction in the x, y plane is -y; the opposite ray is +y
    p0 = np.array([-2.0, 0.5, 0.0])
    for x, wraps in ((0.01, True), (-0.01, False)):  # p1 just right / left of the ray x = 0, y > 0
        p1 = np.array([x, 2.0, 1.0])
        w = wrap_cylinder(p0, p1, r, side=side)
        s = side[:2] / np.linalg.norm(side[:2]) * r
        winding = _turn(p0[:2], s) + _turn(s, p1[:2])
        alphas = math.acos(r / np.linalg.norm(p0[:2])) + math.acos(r / np.linalg.norm(p1[:2]))
        assert w.engaged == wraps == (abs(winding) > alphas)
        if wraps:  # counter-clockwise round the bottom, 163 degrees of arc
            a = r * (abs(winding) - alphas)
            assert a > 2.8
            assert w.arc == pytest.approx(math.hypot(a, w.t1[2] - w.t0[2]), rel=1e-14)
            assert _turn(p0[:2], w.t0[:2]) > 0 and _turn(w.t1[:2], p1[:2]) > 0


def test_inside_side_point_touches_the_circle_once():
    r = 1.0
    p0, p1 = np.array([-2.0, 1.4, 0.0]), np.array([2.5, 1.2, 0.0])   # the line misses the circle
    w = wrap_cylinder(p0, p1, r, side=[0.0, 0.2, 0.0])
    assert w.engaged and w.arc == 0.0 and np.array_equal(w.t0, w.t1)
    t = w.t0
    assert math.hypot(t[0], t[1]) == pytest.approx(r, abs=1e-14)
    n = t / np.linalg.norm(t)   # equal angles to the normal (MuJoCo's Newton tolerance: 1e-6)
    assert _angle(p0 - t, n) == pytest.approx(_angle(p1 - t, n), abs=1e-5)
    assert not wrap_cylinder([-2.0, 0.1, 0.0], [2.5, 0.2, 0.0], r, side=[0.0, 0.2, 0.0]).engaged
    # the inside test takes the side point's full 3-D norm, also for a cylinder
    out = wrap_cylinder(p0, p1, r, side=[0.0, 0.2, 3.0])
    assert not out.engaged  # outside: a side point on the line's side does not force a wrap


def test_length_is_continuous_where_a_wrap_engages():
    r = 1.0

    def length(h):
        p0, p1 = np.array([-2.0, h, 0.0]), np.array([3.0, h, 0.5])
        w = wrap_sphere(p0, p1, r)
        if not w.engaged:
            return np.linalg.norm(p1 - p0), False
        return np.linalg.norm(w.t0 - p0) + w.arc + np.linalg.norm(p1 - w.t1), True

    in_plane = 1.0 / math.hypot(5.0, 0.5)  # the line's distance to the y axis
    h_touch = math.sqrt(r * r - in_plane**2)  # the line touches the sphere
    below, on = length(h_touch * (1 - 1e-9))
    above, off = length(h_touch * (1 + 1e-9))
    assert on and not off
    assert below == pytest.approx(above, abs=1e-7)


def test_bad_elements_raise_model_error():
    x = np.zeros(3)
    with pytest.raises(ModelError, match="first and last a site"):
        tendon_path([("site", x), ("pulley", 2.0)])
    with pytest.raises(ModelError, match="element 1 \\(geom\\): expected a site on either side"):
        tendon_path([("site", x), ("geom", "sphere", np.eye(3), x, 0.1, None), ("pulley", 2.0),
                     ("site", x)])
    with pytest.raises(ModelError, match="kind 'sphere' or 'cylinder'"):
        tendon_path([("site", x), ("geom", "box", np.eye(3), x, 0.1, None), ("site", x)])
    with pytest.raises(ModelError, match="positive divisor"):
        tendon_path([("site", x), ("site", x), ("pulley", 0.0), ("site", x), ("site", x)])
    with pytest.raises(ModelError, match="positive radius"):
        wrap_sphere([1, 0, 0], [0, 1, 0], -1.0)
    with pytest.raises(ModelError, match="element 0"):
        tendon_path([("via", x), ("site", x)])


# ------------------------------------------------------------------ MuJoCo as the reference

SITE, PULLEY = int(mujoco.mjtWrap.mjWRAP_SITE), int(mujoco.mjtWrap.mjWRAP_PULLEY)
SPHERE, CYLINDER = int(mujoco.mjtWrap.mjWRAP_SPHERE), int(mujoco.mjtWrap.mjWRAP_CYLINDER)


def mj_elements(m, d, t):
    """Tendon ``t`` of a compiled MjModel as ``tendon_path`` elements, with each element's body id
    (-1 for a pulley) and MuJoCo's ``wrap_obj`` code for each element (-1 site, -2 pulley, geom id)."""
    elements, bodies, objs = [], [], []
    for k in range(m.tendon_adr[t], m.tendon_adr[t] + m.tendon_num[t]):
        typ, obj, prm = int(m.wrap_type[k]), int(m.wrap_objid[k]), float(m.wrap_prm[k])
        if typ == SITE:
            elements.append(("site", d.site_xpos[obj].copy()))
            bodies.append(int(m.site_bodyid[obj]))
            objs.append(-1)
        elif typ in (SPHERE, CYLINDER):
            side = int(round(prm))
            elements.append(("geom", "sphere" if typ == SPHERE else "cylinder",
                             d.geom_xmat[obj].reshape(3, 3).copy(), d.geom_xpos[obj].copy(),
                             float(m.geom_size[obj, 0]), d.site_xpos[side].copy() if side >= 0 else None))
            bodies.append(int(m.geom_bodyid[obj]))
            objs.append(obj)
        elif typ == PULLEY:
            elements.append(("pulley", prm))
            bodies.append(-1)
            objs.append(-2)
        else:
            raise AssertionError(f"tendon {t}: wrap type {typ} is not spatial")
    return elements, bodies, objs


def ten_J_dense(m, d):
    """MuJoCo 4.0 stores ``ten_J`` as compressed rows: expand it to (ntendon, nv)."""
    J = np.zeros((m.ntendon, m.nv))
    for i in range(m.ntendon):
        a, n = m.ten_J_rowadr[i], m.ten_J_rownnz[i]
        J[i, m.ten_J_colind[a:a + n]] = d.ten_J[a:a + n]
    return J


def our_jacobian(m, d, path, bodies):
    """``sum scale u^T (J_b - J_a)`` over the straight segments, ``J`` MuJoCo's point Jacobians."""
    row, ja, jb = np.zeros(m.nv), np.zeros((3, m.nv)), np.zeros((3, m.nv))
    for a_elem, a, b_elem, b, scale in path.segments:
        u = b - a
        norm = np.linalg.norm(u)
        if norm == 0.0:
            continue
        mujoco.mj_jac(m, d, ja, None, a, bodies[a_elem])
        mujoco.mj_jac(m, d, jb, None, b, bodies[b_elem])
        row += scale * (u / norm) @ (jb - ja)
    return row


def compare(m, d, errors, engaged=None):
    """Every spatial tendon of ``m`` at the state in ``d`` (after ``mj_forward``): fold the errors
    into ``errors`` and count, per tendon, the states where at least one wrap is engaged."""
    J = ten_J_dense(m, d)
    wrap_xpos = d.wrap_xpos.reshape(-1, 3)
    for t in range(m.ntendon):
        if int(m.wrap_type[m.tendon_adr[t]]) == int(mujoco.mjtWrap.mjWRAP_JOINT):
            continue
        elements, bodies, objs = mj_elements(m, d, t)
        path = tendon_path(elements)
        L = d.ten_length[t]
        errors["length"] = max(errors["length"], abs(path.length - L) / max(1.0, abs(L)))
        adr, num = d.ten_wrapadr[t], d.ten_wrapnum[t]
        assert path.wrap_points.shape == (num, 3), f"tendon {t}"
        assert [objs[e] for e in path.wrap_elems] == list(d.wrap_obj.reshape(-1)[adr:adr + num])
        errors["points"] = max(errors["points"], np.abs(path.wrap_points - wrap_xpos[adr:adr + num]).max())
        errors["J"] = max(errors["J"], np.abs(our_jacobian(m, d, path, bodies) - J[t]).max())
        if engaged is not None:
            engaged[t] = engaged.get(t, 0) + bool(path.arcs)


def random_quat(rng, max_angle):
    axis = rng.normal(size=3)
    angle = rng.uniform(0, max_angle)
    return np.r_[math.cos(angle / 2), math.sin(angle / 2) * axis / np.linalg.norm(axis)]


def random_qpos(m, rng):
    """Hinge and slide joints uniform in their ranges (±pi when unlimited), ball joints up to 2 rad."""
    q = m.qpos0.copy()
    for j in range(m.njnt):
        a, typ = m.jnt_qposadr[j], int(m.jnt_type[j])
        if typ == int(mujoco.mjtJoint.mjJNT_BALL):
            q[a:a + 4] = random_quat(rng, 2.0)
        elif typ in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            lo, hi = m.jnt_range[j] if m.jnt_limited[j] else (-math.pi, math.pi)
            q[a] = rng.uniform(lo, hi)
        else:
            raise AssertionError(f"joint {j}: type {typ} is not sampled here")
    return q


ARM = """
<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <site name="top" pos="0 0 0.6"/>
    <site name="front" pos="0.15 0.02 0.4"/>
    <body name="upper">
      <joint name="shoulder" type="ball"/>
      <geom name="ball" type="sphere" size="0.08"/>
      <geom name="shaft" type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02"/>
      <geom name="elbowcyl" type="cylinder" size="0.03 0.05" pos="0 0 -0.3" euler="1.5707963267948966 0 0"/>
      <site name="side_out" pos="0.2 0.03 0"/>
      <site name="side_in" pos="0.02 0.01 0.01"/>
      <site name="inner" pos="0.01 0.02 0"/>
      <site name="mid" pos="0.05 0 -0.15"/>
      <site name="cyl_back" pos="-0.1 0 -0.3"/>
      <site name="cyl_in" pos="0.01 0.005 -0.3"/>
      <site name="cyl_far" pos="0.01 0.06 -0.3"/>
      <body name="fore" pos="0 0 -0.3">
        <joint name="elbow" type="hinge" axis="0 1 0" range="-2.5 2.5"/>
        <geom name="forearm" type="capsule" fromto="0 0 0 0 0 -0.25" size="0.015"/>
        <geom name="wrist" type="sphere" size="0.02" pos="0 0 -0.25"/>
        <site name="ins" pos="0.03 0 -0.2"/>
        <site name="ins2" pos="-0.03 0.01 -0.22"/>
        <body name="hand" pos="0 0 -0.25">
          <joint name="wrist" type="hinge" axis="1 0 0" range="-1.5 1.5"/>
          <geom name="palm" type="box" size="0.02 0.01 0.04" pos="0 0 -0.04"/>
          <site name="tip" pos="0.0 0.02 -0.08"/>
        </body>
      </body>
    </body>
  </worldbody>
  <tendon>
    <spatial name="sphere"><site site="top"/><geom geom="ball"/><site site="mid"/></spatial>
    <spatial name="sphere_side"><site site="front"/><geom geom="ball" sidesite="side_out"/><site site="mid"/></spatial>
    <spatial name="sphere_in"><site site="front"/><geom geom="ball" sidesite="side_in"/><site site="mid"/></spatial>
    <spatial name="end_inside"><site site="top"/><geom geom="ball"/><site site="inner"/></spatial>
    <spatial name="cyl"><site site="mid"/><geom geom="elbowcyl"/><site site="ins"/></spatial>
    <spatial name="cyl_side"><site site="mid"/><geom geom="elbowcyl" sidesite="cyl_back"/><site site="ins"/></spatial>
    <spatial name="cyl_in"><site site="mid"/><geom geom="elbowcyl" sidesite="cyl_in"/><site site="ins2"/></spatial>
    <spatial name="cyl_far"><site site="mid"/><geom geom="elbowcyl" sidesite="cyl_far"/><site site="ins2"/></spatial>
    <spatial name="two_wraps">
      <site site="front"/><geom geom="ball" sidesite="side_out"/><site site="mid"/>
      <geom geom="elbowcyl"/><site site="ins"/><geom geom="wrist"/><site site="tip"/>
    </spatial>
    <spatial name="pulley">
      <site site="top"/><site site="mid"/>
      <pulley divisor="2"/>
      <site site="mid"/><geom geom="elbowcyl"/><site site="ins"/>
      <pulley divisor="2"/>
      <site site="mid"/><geom geom="elbowcyl" sidesite="cyl_back"/><site site="ins2"/>
      <site site="tip"/>
    </spatial>
  </tendon>
</mujoco>
"""


def test_small_model_matches_mujoco():
    m = mujoco.MjModel.from_xml_string(ARM)
    engaged = _check_random_states(m, 7, N_STATES)
    names = [m.tendon(t).name for t in range(m.ntendon)]
    counts = {names[t]: c for t, c in engaged.items()}
    assert counts["end_inside"] == 0  # an end point inside the sphere never wraps
    for name in ("sphere", "sphere_side", "sphere_in", "cyl", "cyl_side", "cyl_in", "cyl_far", "pulley"):
        assert 0 < counts[name] < N_STATES, (name, counts)  # engages and disengages


CLOUD = """
<mujoco>
  <worldbody>
    <site name="a" pos="-0.3 0.04 0.02"/>
    <body name="geoms">
      <joint name="turn" type="ball"/>
      <geom name="ball" type="sphere" size="0.1"/>
      <geom name="cyl" type="cylinder" size="0.08 0.1" pos="0 0 0"/>
      <site name="out" pos="0.05 -0.25 0.1"/>
      <site name="in" pos="0.01 0.03 -0.02"/>
      <site name="far" pos="0.02 0.01 0.3"/>
    </body>
    <body name="end">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="y" type="slide" axis="0 1 0"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <geom size="0.01"/>
      <site name="e" pos="0 0 0"/>
    </body>
  </worldbody>
  <tendon>
    <spatial><site site="a"/><geom geom="ball"/><site site="e"/></spatial>
    <spatial><site site="a"/><geom geom="ball" sidesite="out"/><site site="e"/></spatial>
    <spatial><site site="a"/><geom geom="ball" sidesite="in"/><site site="e"/></spatial>
    <spatial><site site="a"/><geom geom="cyl"/><site site="e"/></spatial>
    <spatial><site site="a"/><geom geom="cyl" sidesite="out"/><site site="e"/></spatial>
    <spatial><site site="a"/><geom geom="cyl" sidesite="in"/><site site="e"/></spatial>
    <spatial><site site="a"/><geom geom="cyl" sidesite="far"/><site site="e"/></spatial>
  </tendon>
</mujoco>
"""


def test_random_end_points_round_spheres_and_cylinders_match_mujoco():
    """The free end anywhere in a box round the geoms (also inside them), the geoms turned at random:
    every kind of wrap, with no side site, one outside, one inside, and one whose projection is inside
    the circle but whose 3-D distance is not (it counts as outside)."""
    m = mujoco.MjModel.from_xml_string(CLOUD)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(3)
    errors, engaged, n = {"length": 0.0, "points": 0.0, "J": 0.0}, {}, 300
    for k in range(n):
        d.qpos[:4] = random_quat(rng, math.pi)
        d.qpos[4:] = rng.uniform(-0.4, 0.4, 3) * (0.3 if k % 4 == 0 else 1.0)
        mujoco.mj_forward(m, d)
        compare(m, d, errors, engaged)
    assert errors["length"] < 1e-12 and errors["points"] < 1e-12 and errors["J"] < 1e-10, errors
    assert all(0.05 * n < c < 0.95 * n for c in engaged.values()), engaged


def _cyl_at(m, d, q):
    """Our path of tendon ``cyl`` with the elbow at ``q``: (engaged, length, dL/dq_elbow)."""
    d.qpos[:] = m.qpos0
    d.qpos[m.joint("elbow").qposadr[0]] = q
    mujoco.mj_forward(m, d)
    elements, bodies, _ = mj_elements(m, d, m.tendon("cyl").id)
    path = tendon_path(elements)
    return bool(path.arcs), path.length, our_jacobian(m, d, path, bodies)[m.joint("elbow").dofadr[0]]


def test_sweep_through_wrap_onset_matches_mujoco_and_length_is_c1():
    m = mujoco.MjModel.from_xml_string(ARM)
    d = mujoco.MjData(m)
    elbow, wrist = m.joint("elbow").qposadr[0], m.joint("wrist").qposadr[0]
    qs, errors = np.linspace(-2.5, 2.5, 401), {"length": 0.0, "points": 0.0, "J": 0.0}
    engaged = []
    for q in qs:
        d.qpos[:] = m.qpos0
        d.qpos[elbow], d.qpos[wrist] = q, 0.3
        mujoco.mj_forward(m, d)
        compare(m, d, errors)
        engaged.append(_cyl_at(m, d, q)[0])
    assert errors["length"] < 1e-12 and errors["points"] < 1e-12 and errors["J"] < 1e-10, errors
    onsets = np.flatnonzero(np.diff(engaged))
    assert len(onsets) == 2  # engages, then disengages
    for k in onsets:  # bisect to the onset: L and dL/dq continuous there, d2L/dq2 jumps
        lo, hi = qs[k], qs[k + 1]
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _cyl_at(m, d, mid)[0] == engaged[k] else (lo, mid)
        (_, l_lo, j_lo), (_, l_hi, j_hi) = _cyl_at(m, d, lo - 1e-8), _cyl_at(m, d, hi + 1e-8)
        assert abs(l_hi - l_lo) < 1e-9 and abs(j_hi - j_lo) < 1e-7
        slope_lo = (j_lo - _cyl_at(m, d, lo - 1e-4)[2]) / 1e-4
        slope_hi = (_cyl_at(m, d, hi + 1e-4)[2] - j_hi) / 1e-4
        assert abs(slope_hi - slope_lo) > 0.05  # wrapped: moment arm = radius (slope 0); straight: 0.087


def _myo():
    return pytest.importorskip("myo_sim", reason="MyoSuite's models (myo_sim) are not installed")


@pytest.fixture(scope="module")
def myoarm(tmp_path_factory):
    import contextlib
    import warnings

    sim = _myo()
    # composing the arm logs a warning: keep MUJOCO_LOG.TXT in a temporary folder
    with contextlib.chdir(tmp_path_factory.mktemp("myoarm")), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "Attaching a spec with an empty prefix ..."
        xml = sim.load_spec("myoarm_r").to_xml()
        return mujoco.MjModel.from_xml_string(xml)


def _check_random_states(m, seed, n=N_STATES_MYO):
    """Our paths against MuJoCo's at ``n`` random states: lengths, tangent points and ``ten_J``; how
    often each tendon's wraps engaged."""
    d = mujoco.MjData(m)
    rng = np.random.default_rng(seed)
    errors, engaged = {"length": 0.0, "points": 0.0, "J": 0.0}, {}
    for _ in range(n):
        d.qpos[:] = random_qpos(m, rng)
        mujoco.mj_forward(m, d)
        compare(m, d, errors, engaged)
    assert errors["length"] < 1e-12 and errors["points"] < 1e-12 and errors["J"] < 1e-10, errors
    return engaged


@pytest.mark.parametrize("name", ["myoelbow", "myofinger"])
def test_myosuite_legacy_models_match_mujoco(name):
    m = mujoco.MjModel.from_xml_path(str(_myo().get_xml_path(name)))
    engaged = _check_random_states(m, 11)
    assert any(0 < c < N_STATES_MYO for c in engaged.values())
    if name == "myofinger":
        assert PULLEY in set(int(w) for w in m.wrap_type)


def test_myoarm_matches_mujoco(myoarm):
    assert myoarm.ntendon == 67
    engaged = _check_random_states(myoarm, 13)
    assert sum(0 < c < N_STATES_MYO for c in engaged.values()) >= 10
