"""OpenSim muscle paths computed by our route pass against OpenSim 4.6 itself: lengths (``getLength``)
and moment arms (``computeMomentArm`` = -dl/dq) at random states of tiny models built with OpenSim's
API (two bodies on PinJoints, path points of every kind, wraps over spheres and cylinders with
quadrants and ranges), read back from their ``.osim`` by :func:`mcdm_pin.osim.paths.read_paths` onto
a pin model built here; and moving points' own term against finite differences."""

import math
import shutil
from pathlib import Path
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin.model import CableSet, cable_jacobian, cable_lengths
from mcdm_pin.osim import speeds
from mcdm_pin.osim.paths import read_paths, simm_spline

osim = pytest.importorskip("opensim")
osim.Logger.removeFileSink()  # OpenSim would append to an opensim.log beside the model it loads
osim.Logger.setLevelString("warn")

RNG = np.random.default_rng(24)
# (parent, child, location and orientation (XYZ body-fixed) of the joint frame in the parent, and in the
# child); the joints are PinJoints about their frames' z axis
JOINTS = (("ground", "b1", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), "q1"),
          ("b1", "b2", (0.3, 0.0, 0.0), (0.4, -0.3, 0.2), (-0.02, 0.01, 0.0), (0.1, 0.25, -0.3), "q2"))
RANGES = {"q1": (-1.0, 1.2), "q2": (-0.8, 1.5)}


def _xyz(a, b, c):
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return (np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]]) @ np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
            @ np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]]))


def _pin_model():
    """The same chain in Pinocchio: one frame per body (and ground) at the OpenSim body frame."""
    model = pin.Model()
    model.addFrame(pin.Frame("ground", 0, 0, pin.SE3.Identity(), pin.FrameType.BODY))
    joint_of = {"ground": 0}
    for parent, child, loc, ori, child_loc, child_ori, coord in JOINTS:
        pj = joint_of[parent]
        parent_body = model.frames[model.getFrameId(parent)].placement
        jid = model.addJoint(pj, pin.JointModelRZ(), parent_body * pin.SE3(_xyz(*ori), np.array(loc)), coord)
        body = pin.SE3(_xyz(*child_ori), np.array(child_loc)).inverse()
        model.appendBodyToJoint(jid, pin.Inertia.FromSphere(1.0, 0.05), body)
        model.addFrame(pin.Frame(child, jid, 0, body, pin.FrameType.BODY))
        joint_of[child] = jid
    return model


def _chain(m):
    """The chain of :data:`JOINTS` in the OpenSim model ``m``: its bodies (``ground`` included) and
    coordinates by name."""
    bodies, coords = {"ground": m.getGround()}, {}
    for parent, child, loc, ori, child_loc, child_ori, coord in JOINTS:
        b = osim.Body(child, 1.0, osim.Vec3(0), osim.Inertia(0.01, 0.01, 0.01))
        j = osim.PinJoint(f"j_{child}", bodies[parent], osim.Vec3(*loc), osim.Vec3(*ori), b,
                          osim.Vec3(*child_loc), osim.Vec3(*child_ori))
        j.updCoordinate().setName(coord)
        m.addBody(b)
        m.addJoint(j)
        bodies[child] = b
        coords[coord] = j.updCoordinate()
    return bodies, coords


def _osim_model(muscles, wraps):
    """An OpenSim model of the chain; ``wraps``: (kind, name, body, radius, length, translation,
    rotation, quadrant); ``muscles``: (name, points, wrap names with ranges)."""
    m = osim.Model()
    bodies, coords = _chain(m)
    for coord, c in coords.items():
        c.setRangeMin(RANGES[coord][0])
        c.setRangeMax(RANGES[coord][1])
        c.set_clamped(False)
    objects = {}
    for kind, name, body, radius, length, tr, rot, quadrant in wraps:
        w = {"sphere": osim.WrapSphere, "cylinder": osim.WrapCylinder, "ellipsoid": osim.WrapEllipsoid}[kind]()
        w.setName(name)
        if kind == "ellipsoid":
            w.set_dimensions(osim.Vec3(*radius))
        else:
            w.set_radius(radius)
        if kind == "cylinder":
            w.set_length(length)
        w.set_translation(osim.Vec3(*tr))
        w.set_xyz_body_rotation(osim.Vec3(*rot))
        w.set_quadrant(quadrant)
        bodies[body].addWrapObject(w)
        objects[name] = w
    forces = []
    for name, points, pw in muscles:
        mus = osim.Thelen2003Muscle(name, 100.0, 0.1, 0.1, 0.0)
        path = mus.updGeometryPath()
        for i, p in enumerate(points):
            if p[0] == "point":
                path.appendNewPathPoint(f"{name}-P{i}", bodies[p[1]], osim.Vec3(*p[2]))
            elif p[0] == "conditional":
                c = osim.ConditionalPathPoint()
                c.setName(f"{name}-P{i}")
                c.setParentFrame(bodies[p[1]])
                c.set_location(osim.Vec3(*p[2]))
                c.setCoordinate(coords[p[3]])
                c.setRangeMin(p[4][0])
                c.setRangeMax(p[4][1])
                path.updPathPointSet().adoptAndAppend(c)
            else:  # moving: per axis (x knots, y values)
                mp = osim.MovingPathPoint()
                mp.setName(f"{name}-P{i}")
                mp.setParentFrame(bodies[p[1]])
                for axis, (xs, ys) in zip("xyz", p[2]):
                    f = osim.SimmSpline()
                    for x, y in zip(xs, ys):
                        f.addPoint(x, y)
                    getattr(mp, f"set_{axis}_location")(f)
                    getattr(mp, f"set{axis.upper()}Coordinate")(coords[p[3]])
                path.updPathPointSet().adoptAndAppend(mp)
        for wname, rng, *method in pw:
            path.addPathWrap(objects[wname])
            n = path.getWrapSet().getSize()
            path.updWrapSet().get(n - 1).set_range(0, rng[0])
            path.updWrapSet().get(n - 1).set_range(1, rng[1])
            if method:
                path.updWrapSet().get(n - 1).set_method(method[0])
        m.addForce(mus)
        forces.append(mus)
    return m, forces, coords


def _compare(tmp_path, muscles, wraps, n_states=30, rtol=1e-9):
    """Lengths and moment arms, ours against OpenSim's, at random states (q beyond the coordinates'
    ranges too: moving points clamp there)."""
    m, forces, coords = _osim_model(muscles, wraps)
    file = tmp_path / "tiny.osim"
    m.finalizeConnections()
    m.printToXML(str(file))
    m = osim.Model(str(file))
    state = m.initSystem()
    model = _pin_model()
    cables, _, _ = read_paths(ET.parse(file).getroot(), str(file), model)
    cs = CableSet(model, cables)
    data = model.createData()
    names = [c.name for c in cables]
    worst_l, worst_r = 0.0, 0.0
    for _ in range(n_states):
        q = RNG.uniform(-1.6, 1.8, size=2)
        for k, name in enumerate(("q1", "q2")):
            m.getCoordinateSet().get(name).setValue(state, q[k], False)
        m.realizePosition(state)
        ours_l = cable_lengths(model, data, cs, q)
        ours_L = cable_jacobian(model, data, cs, q)
        for i, name in enumerate(names):
            mus = osim.Muscle.safeDownCast(m.getForceSet().get(name))
            ref = mus.getLength(state)
            worst_l = max(worst_l, abs(ours_l[i] - ref) / ref)
            for k, cname in enumerate(("q1", "q2")):
                arm = mus.computeMomentArm(state, m.getCoordinateSet().get(cname))
                worst_r = max(worst_r, abs(-ours_L[i, k] - arm) / max(1e-3, abs(arm)))
    assert worst_l < rtol and worst_r < rtol, (worst_l, worst_r)
    return worst_l, worst_r


SPLINE = ((-1.0, 0.0, 0.7, 1.2), (0.02, 0.03, 0.05, 0.04))


def test_points_of_every_kind(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    moving = ("moving", "b2", (SPLINE, ((-1, 1.5), (0.01, -0.01)), ((-1.0, 0.5, 1.5), (0.0, 0.02, 0.01))), "q2")
    muscles = [("m1", [("point", "ground", (0.05, 0.1, 0.0)), ("conditional", "b1", (0.2, 0.04, 0.01), "q1",
                                                                 (-0.5, 0.6)),
                       moving, ("point", "b2", (0.1, 0.02, -0.01))], []),
               ("m2", [("point", "b1", (0.1, -0.03, 0.02)), moving, ("conditional", "b2", (0.12, 0.0, 0.03), "q2",
                                                                      (0.0, 2.0))], [])]
    _compare(tmp_path, muscles, [])


@pytest.mark.parametrize("quadrant", ["all", "+x", "-y"])
def test_sphere_and_cylinder_wraps(tmp_path, monkeypatch, quadrant):
    monkeypatch.chdir(tmp_path)
    wraps = [("sphere", "S", "b1", 0.04, 0.0, (0.3, 0.0, 0.0), (0.2, 0.1, -0.3), quadrant),
             ("cylinder", "C", "ground", 0.03, 0.2, (0.0, 0.0, 0.0), (0.3, -0.2, 0.1), quadrant)]
    muscles = [("single", [("point", "ground", (0.1, 0.1, 0.0)), ("point", "b2", (0.15, 0.0, 0.01))], [("S", (-1, -1))]),
               ("double", [("point", "ground", (-0.05, 0.06, 0.01)), ("point", "b1", (0.15, 0.05, 0.0)),
                           ("point", "b2", (0.2, -0.02, 0.0))], [("C", (1, 2)), ("S", (2, 3))]),
               ("cyl", [("point", "ground", (0.05, -0.1, 0.02)), ("point", "b1", (0.2, 0.06, 0.0))], [("C", (-1, -1))])]
    _compare(tmp_path, muscles, wraps)


@pytest.mark.parametrize("quadrant", ["all", "+x", "-z"])
def test_ellipsoid_wraps(tmp_path, monkeypatch, quadrant):
    """OpenSim's iterative ellipsoid wrap (hybrid, midpoint and axial methods), alone and with a
    cylinder on the same path: our code takes OpenSim's own iterations, so the agreement is to
    rounding, not to OpenSim's tolerances (squared residual 1e-8 for the tangent points, a 1 mm
    polyline for the surface path)."""
    monkeypatch.chdir(tmp_path)
    wraps = [("ellipsoid", "E", "b1", (0.05, 0.03, 0.07), 0.0, (0.3, 0.0, 0.0), (0.2, 0.1, -0.3), quadrant),
             ("cylinder", "C", "ground", 0.03, 0.2, (0.0, 0.0, 0.0), (0.3, -0.2, 0.1), "all")]
    muscles = [(f"e_{method}", [("point", "ground", (0.1, 0.1, 0.0)), ("point", "b2", (0.15, 0.0, 0.01))],
                [("E", (-1, -1), method)]) for method in ("hybrid", "midpoint", "axial")]
    muscles.append(("two", [("point", "ground", (-0.05, 0.06, 0.01)), ("point", "b1", (0.15, 0.05, 0.0)),
                            ("point", "b2", (0.2, -0.02, 0.0))], [("C", (1, 2)), ("E", (2, 3))]))
    _compare(tmp_path, muscles, wraps, rtol=1e-6)


def test_the_fan_in_sweeps_is_the_sample_loop_to_the_bit():
    """The hybrid method's fan (298 nearest points; :func:`_fan_sum` runs their Newton iterations in
    sweeps over all of them) equals OpenSim's loop over the samples, each through
    ``findClosestPoint``, to the bit, in Python and compiled as the route kernel compiles it
    (``error_model="numpy"``: the sweeps become vector instructions): segments through and outside
    the ellipsoid, and one with a sample on a coordinate plane (the special case that takes the 2-d
    ellipse)."""
    from mcdm_pin.model import wrapping_osim_ellipsoid as we
    from mcdm_pin.model.wrapping_osim import _add, _mul, _sub, _unit, _ZERO

    def loop(dims, a, r1, r1r2, prev):
        vsum = _ZERO
        for i in range(1, we.NUM_FAN_SAMPLES - 1):
            sv = _add(r1, _mul(r1r2, i / we.NUM_FAN_SAMPLES))
            prev = we._closest_on_ellipsoid(dims, a[0], a[1], a[2], sv[0], sv[1], sv[2], -1, prev)
            vsum = _add(vsum, _unit(_sub(prev, sv)))
        return vsum

    rng = np.random.default_rng(7)
    dims = (0.0765, 0.174, 0.075)
    f = 3.0 / sum(dims)
    a = tuple(d * f for d in dims)
    cases = [((-0.8, 0.3, 0.2), (1.6, 0.0, 0.0))]  # the sample i = 150 has u = 0 exactly
    cases += [(tuple(rng.uniform(-1.5, 1.5, 3)), tuple(rng.uniform(-3.0, 3.0, 3))) for _ in range(20)]
    numba = pytest.importorskip("numba")
    compiled = numba.njit(error_model="numpy")(lambda d, a, r1, r1r2, prev: we._fan_sum(d, a, r1, r1r2, prev))
    for r1, r1r2 in cases:
        expected = loop(dims, a, r1, r1r2, _ZERO)
        assert we._fan_sum(dims, a, r1, r1r2, _ZERO) == expected
        assert compiled(dims, a, r1, r1r2, _ZERO) == expected


def test_moving_point_term_is_the_derivative(tmp_path, monkeypatch):
    """L of a path with a moving point against central differences of our lengths."""
    monkeypatch.chdir(tmp_path)
    moving = ("moving", "b2", (SPLINE, ((-1, 1.5), (0.01, -0.01)), ((-1.0, 0.5, 1.5), (0.0, 0.02, 0.01))), "q2")
    m, _, _ = _osim_model([("m", [("point", "b1", (0.1, 0.03, 0.0)), moving], [])], [])
    file = tmp_path / "m.osim"
    m.finalizeConnections()
    m.printToXML(str(file))
    model = _pin_model()
    cs = CableSet(model, read_paths(ET.parse(file).getroot(), str(file), model)[0])
    data = model.createData()
    h = 1e-6
    for _ in range(10):
        q = RNG.uniform(-0.7, 1.1, size=2)
        L = cable_jacobian(model, data, cs, q)[0]
        fd = [(cable_lengths(model, data, cs, q + h * e)[0] - cable_lengths(model, data, cs, q - h * e)[0]) / (2 * h)
              for e in np.eye(2)]
        assert np.allclose(L, fd, rtol=1e-7, atol=1e-9)


def test_simm_spline_matches_opensim():
    x, y = (-1.0, -0.2, 0.3, 0.9, 1.7), (0.1, -0.05, 0.2, 0.0, 0.3)
    ours = simm_spline(x, y)
    ref = osim.SimmSpline()
    for a, b in zip(x, y):
        ref.addPoint(a, b)
    from mcdm_pin.osim.paths import _eval

    for t in np.linspace(-1.5, 2.0, 23):
        assert abs(_eval(ours, t) - ref.calcValue(osim.Vector(1, t))) < 1e-13


def _muscle_model(kind, tmp_path, lo, ls, damping):
    m = osim.Model()
    bodies, _ = _chain(m)
    if kind == "Thelen2003Muscle":
        mus = osim.Thelen2003Muscle("mus", 500.0, lo, ls, 0.25)
        mus.set_Af(0.3)
        mus.set_Flen(1.8)
        mus.set_KshapeActive(0.5)
        mus.set_KshapePassive(4.0)
        mus.set_minimum_activation(0.02)
        mus.setMinControl(0.02)
    elif kind == "Millard2012EquilibriumMuscle":
        mus = osim.Millard2012EquilibriumMuscle("mus", 500.0, lo, ls, 0.25)
        mus.set_ignore_tendon_compliance(True)
        mus.set_fiber_damping(damping)
    else:
        mus = osim.DeGrooteFregly2016Muscle()
        mus.setName("mus")
        mus.set_max_isometric_force(500.0)
        mus.set_optimal_fiber_length(lo)
        mus.set_tendon_slack_length(ls)
        mus.set_pennation_angle_at_optimal(0.25)
        mus.set_ignore_tendon_compliance(True)
        mus.set_fiber_damping(damping)
        mus.set_active_force_width_scale(1.2)
    mus.addNewPathPoint("p1", bodies["ground"], osim.Vec3(-0.1, 0.12, 0.0))
    mus.addNewPathPoint("p2", bodies["b2"], osim.Vec3(0.1, 0.03, 0.01))
    m.addForce(mus)
    m.finalizeConnections()
    file = tmp_path / "muscle.osim"
    m.printToXML(str(file))
    return file


@pytest.mark.parametrize("kind,damping", [("Millard2012EquilibriumMuscle", 0.1),
                                          ("Millard2012EquilibriumMuscle", 0.0),
                                          ("DeGrooteFregly2016Muscle", 0.05)])
def test_muscle_force_bounds(tmp_path, monkeypatch, kind, damping):
    """Tension at activation 0 (OpenSim clamps it to its minimum) and 1, rigid tendon, against
    OpenSim's ``getTendonForce``, and the curves' multipliers against OpenSim's own."""
    from mcdm_pin.model.muscles import force_range

    monkeypatch.chdir(tmp_path)
    model = _pin_model()
    data = model.createData()
    probe = CableSet(model, read_paths(ET.parse(_muscle_model(kind, tmp_path, 0.1, 0.1, damping)).getroot(), "p",
                                       model)[0])
    qs = RNG.uniform(-0.6, 0.9, size=(40, 2))
    lengths = np.array([cable_lengths(model, data, probe, q)[0] for q in qs])
    lo = (lengths.max() - lengths.min()) / 1.1
    ls = lengths.min() - 0.45 * lo
    file = _muscle_model(kind, tmp_path, lo, ls, damping)
    cables, muscles, _ = read_paths(ET.parse(file).getroot(), str(file), model)
    cs = CableSet(model, cables, muscles=muscles, muscle_cables=muscles.names)
    m = osim.Model(str(file))
    s = m.initSystem()
    mus = osim.Muscle.safeDownCast(m.getForceSet().get("mus"))
    worst = 0.0
    for q in qs:
        qd = RNG.normal(0.0, 3.0, size=2)
        for k, name in enumerate(("q1", "q2")):
            m.getCoordinateSet().get(name).setValue(s, q[k], False)
            m.getCoordinateSet().get(name).setSpeedValue(s, qd[k])
        ell = cable_lengths(model, data, cs, q)
        ell_dot = cable_jacobian(model, data, cs, q) @ qd
        state = force_range(muscles, ell, ell_dot)
        l, v, cos_a, _ = muscles.fiber(ell, ell_dot)
        for a, ours in ((0.0, state.f_min[0]), (1.0, state.f_max[0])):
            mus.setActivation(s, a)
            m.realizeDynamics(s)
            ref = mus.getTendonForce(s)
            worst = max(worst, abs(ours - ref) / max(1.0, abs(ref)))
        assert abs(l[0] - mus.getNormalizedFiberLength(s)) < 1e-10
        assert abs(v[0] - mus.getNormalizedFiberVelocity(s)) < 1e-10
        assert abs(mus.getActiveForceLengthMultiplier(s) * mus.getForceVelocityMultiplier(s) * 500.0 * cos_a[0]
                   - state.gain[0]) < 1e-9 * 500.0
    assert worst < 1e-9, worst


def test_thelen_force_range(tmp_path, monkeypatch):
    """Thelen2003Muscle with a rigid tendon against OpenSim's own rigid-tendon force (Static
    Optimization's ``calcInextensibleTendonActiveFiberForce(s, a)``, plus the passive fiber force
    along the tendon at the rigid tendon's fiber length; OpenSim 4.6 refuses
    ``ignore_tendon_compliance`` on a Thelen muscle), at 40 states and activations 0 (clamped to the minimum) to 1: the
    range's ends and the exact tension ``t(a)`` to 1e-9 relative; the chord ``passive + gain a``
    equals ``t`` at the ends only."""
    monkeypatch.chdir(tmp_path)
    model = _pin_model()
    data = model.createData()
    probe = CableSet(model, read_paths(ET.parse(_muscle_model("Thelen2003Muscle", tmp_path, 0.1, 0.1, 0.0))
                                       .getroot(), "p", model)[0])
    qs = RNG.uniform(-0.6, 0.9, size=(40, 2))
    lengths = np.array([cable_lengths(model, data, probe, q)[0] for q in qs])
    lo = (lengths.max() - lengths.min()) / 1.1
    ls = lengths.min() - 0.45 * lo
    file = _muscle_model("Thelen2003Muscle", tmp_path, lo, ls, 0.0)
    cables, muscles, notes = read_paths(ET.parse(file).getroot(), str(file), model)
    assert muscles.thelen.all() and muscles.a_min[0] == 0.02 and not notes
    cs = CableSet(model, cables, muscles=muscles, muscle_cables=muscles.names)
    m = osim.Model(str(file))
    s = m.initSystem()
    mus = osim.Thelen2003Muscle.safeDownCast(m.getForceSet().get("mus"))
    worst, chord, regions = 0.0, 0.0, set()
    for q in qs:
        qd = RNG.normal(0.0, 4.0, size=2)
        for k, name in enumerate(("q1", "q2")):
            m.getCoordinateSet().get(name).setValue(s, q[k], False)
            m.getCoordinateSet().get(name).setSpeedValue(s, qd[k])
        m.realizeVelocity(s)
        ell = cable_lengths(model, data, cs, q)
        ell_dot = cable_jacobian(model, data, cs, q) @ qd
        assert abs(ell[0] - mus.getLength(s)) < 1e-12 and abs(ell_dot[0] - mus.getLengtheningSpeed(s)) < 1e-12
        l, v, cos_a, clamped = muscles.fiber(ell, ell_dot)
        regions.add(int(np.sign(v[0])))
        mus.setFiberLength(s, max(l[0] * lo, mus.getMinimumFiberLength()))
        m.realizeDynamics(s)
        passive = mus.getPassiveFiberForceAlongTendon(s)
        state = force_range_of(muscles, ell, ell_dot)
        for a in (0.0, 0.02, 0.1, 0.35, 0.6, 0.9, 1.0):
            ref = mus.calcInextensibleTendonActiveFiberForce(s, a) + passive
            ours = muscles.tension(ell, ell_dot, np.array([a]))[0]
            worst = max(worst, abs(ours - ref) / max(1.0, abs(ref)))
            chord = max(chord, abs(state.passive[0] + state.gain[0] * max(a, 0.02) - ref) / 500.0)
            if a in (0.0, 1.0):
                end = state.f_min[0] if a == 0.0 else state.f_max[0]
                worst = max(worst, abs(end - ref) / max(1.0, abs(ref)))
    assert regions == {-1, 1}, regions
    assert worst < 1e-9, worst
    assert 1e-3 < chord < 0.1, chord  # the chord is not t(a) in between (docs/opensim.md)


def force_range_of(muscles, ell, ell_dot):
    from mcdm_pin.model.muscles import force_range

    return force_range(muscles, ell, ell_dot)


REPO = Path(__file__).resolve().parents[1]
ARM26 = REPO / "robots" / "opensim" / "arm26.osim"
TSM = REPO / "robots" / "opensim" / "TSM_subject_noWeight.osim"


class Loaded:
    """A committed ``.osim`` on the real loader (:func:`mcdm_pin.osim.load.osim_skeleton`) with its
    muscles read by :func:`read_paths` (coordinates: OpenSim's names -> the loader's ``q``, ``v``
    entries), and OpenSim's own copy (loaded from ``workdir``), its ``PointConstraint``s enforced or not."""

    def __init__(self, path, workdir, enforce=True):
        from mcdm_pin.osim.load import osim_skeleton

        self.om, _, self.src, doc = osim_skeleton(path)
        om = self.om
        self.model, self.data, cv = om.model, om.model.createData(), om.coordinate_v
        coords = {n: (int(om.q_index[v]), int(v)) for n, v in zip(om.coordinates, cv)}
        self.cables, self.muscles, _ = read_paths(doc.root, str(path), self.model, coords)
        self.cs = CableSet(self.model, self.cables)
        self.ellipsoid = np.array([any(getattr(p, "kind", "") == "opensim_ellipsoid" for p in c.route)
                                   for c in self.cables])
        copy = Path(workdir) / f"{'c' if enforce else 'f'}_{Path(path).name}"
        shutil.copyfile(path, copy)
        self.osim = osim.Model(str(copy))
        if not enforce:
            for c in self.osim.getConstraintSet():
                c.set_isEnforced(False)
        self.state = self.osim.initSystem()
        self.coords = [self.osim.getCoordinateSet().get(n) for n in om.coordinates]
        self.paths = [osim.Muscle.safeDownCast(self.osim.getForceSet().get(c.name)) for c in self.cables]

    def random_q(self, rng):
        """A random configuration: unlocked coordinates uniform in their ranges (cut at +-3), on the
        loops (the clavicle and scapula coordinates moved onto them) when the model has some."""
        vals = {}
        for c in self.coords:
            if not c.get_locked():
                vals[c.getName()] = rng.uniform(max(c.getRangeMin(), -3.0), min(c.getRangeMax(), 3.0))
        q = self.src.configuration(vals)
        if self.src.loops is not None:
            names = self.om.coordinates
            q = self.src.loops.project(q, [int(self.om.coordinate_v[k]) for k, n in enumerate(names)
                                           if n.startswith(("clav_", "scapula_"))])
        return q

    def set(self, q):
        om = self.om
        for c, v in zip(self.coords, om.coordinate_v):
            c.setValue(self.state, float(q[om.q_index[v]]), False)
        self.osim.realizePosition(self.state)

    def unit_tension_forces(self, q):
        """OpenSim-speed generalized forces of a unit tension in each cable, ``-(L P)`` (m, nv) with
        ``P = dv/du`` (:mod:`mcdm_pin.osim.speeds`), columns at the coordinates' ``v`` entries."""
        L = cable_jacobian(self.model, self.data, self.cs, q)
        P = np.column_stack([speeds.from_speeds(self.om.angular, q, e) for e in np.eye(self.model.nv)])
        return -(L @ P), P


def _rel(ours, ref, floor):
    return abs(ours - ref) / max(floor, abs(ref))


def _check_paths(loaded, loaded_free, states, rng):
    """Largest relative differences (lengths, moment arms about every unlocked coordinate, and, with
    loops, OpenSim's constrained moment arms), separately for cables over an ellipsoid."""
    worst = {(k, e): 0.0 for k in ("length", "arm", "constrained") for e in (False, True)}
    cv = loaded.om.coordinate_v
    for _ in range(states):
        q = loaded.random_q(rng)
        loaded.set(q)
        lengths = cable_lengths(loaded.model, loaded.data, loaded.cs, q)
        tau, P = loaded.unit_tension_forces(q)
        if loaded_free is not None:
            loaded_free.set(q)
            G = loaded.src.loops.jacobian(q) @ P
        for i, mus in enumerate(loaded.paths):
            e = bool(loaded.ellipsoid[i])
            worst["length", e] = max(worst["length", e], _rel(lengths[i], mus.getLength(loaded.state), 1e-3))
            for k, c in enumerate(loaded.coords):
                if c.get_locked():
                    continue
                if loaded_free is None:
                    worst["arm", e] = max(worst["arm", e], _rel(tau[i, cv[k]], mus.computeMomentArm(loaded.state, c),
                                                                1e-3))
                    continue
                # without the constraint OpenSim's moment arm is the generalized force of a unit tension
                ref = loaded_free.paths[i].computeMomentArm(loaded_free.state, loaded_free.coords[k])
                worst["arm", e] = max(worst["arm", e], _rel(tau[i, cv[k]], ref, 1e-3))
                # with it, MomentArmSolver weighs those forces by the unit speed of the coordinate
                # projected onto the loop (projectU: least squares, unit weights), scaled to 1 there;
                # a coordinate the loop does not see (G e_k = 0) keeps its unit speed: the same arm
                if not G[:, cv[k]].any():
                    continue
                unit = np.zeros(loaded.model.nv)
                unit[cv[k]] = 1.0
                C = unit - G.T @ np.linalg.solve(G @ G.T, G @ unit)
                ref = mus.computeMomentArm(loaded.state, c)
                worst["constrained", e] = max(worst["constrained", e], _rel(C @ tau[i] / C[cv[k]], ref, 1e-3))
    return worst


def test_arm26_muscle_paths_on_the_loader(tmp_path, monkeypatch):
    """Every muscle of arm26 (Thelen muscles; cylinders and ellipsoids, several wraps per path) on the
    real loader: lengths and moment arms at 30 random states against OpenSim's ``getLength`` and
    ``computeMomentArm``: 1e-9 relative (floor 1 mm), 1e-6 for the paths over an ellipsoid (TRIlong, BIClong).

    TRIlong's three wraps need several of OpenSim's rounds: its lengths see the moved tangent points
    at their first (cached) ground positions and its forces act where the wraps last put them
    (docs/opensim.md), both followed here. And the interaction wrenches stay consistent with ``L``:
    ``S^T p = M qdd + h + L^T f`` for each joint."""
    monkeypatch.chdir(tmp_path)
    arm = Loaded(ARM26, tmp_path)
    assert arm.muscles.thelen.all() and arm.ellipsoid.sum() == 2  # TRIlong, BIClong
    worst = _check_paths(arm, None, 30, np.random.default_rng(26))
    assert worst["length", False] < 1e-9 and worst["arm", False] < 1e-9, worst
    assert worst["length", True] < 1e-6 and worst["arm", True] < 1e-6, worst
    from mcdm_pin.model import TermsEvaluator

    model, data, cs = arm.model, arm.data, arm.cs
    ev = TermsEvaluator(model, cs)
    for q in RNG.uniform(0.2, 2.2, size=(5, 2)):
        t = ev(q, RNG.normal(size=2), RNG.normal(size=2))
        f = RNG.uniform(0.0, 100.0, size=cs.m)
        p = t.wrenches(f)
        pin.forwardKinematics(model, data, q)
        for a, j in enumerate(ev.joints):
            S = np.asarray(data.joints[j.child_id].S).reshape(6, -1)
            iv = model.joints[j.child_id].idx_v
            assert np.allclose(S.T @ p[a], (t.tau + t.L.T @ f)[iv:iv + 1], rtol=0, atol=1e-12)


def test_thoracoscapular_muscle_paths_on_the_loader(tmp_path, monkeypatch):
    """Every muscle of the thoracoscapular shoulder (Seth et al. 2019 via RMR, CC BY 4.0: 33 Millard
    muscles, moving points, PathWraps over ellipsoids, cylinders and spheres) on the real loader, at
    30 random states on the acromioclavicular loop: lengths against ``getLength``; moment arms about
    every unlocked coordinate, the clavicle and scapula ones included, two ways, both exact:

    - against OpenSim's ``computeMomentArm`` on its copy with the ``PointConstraint`` not enforced:
      MomentArmSolver's coupling vector is then the coordinate's unit speed, so its moment arm is the
      generalized force of a unit tension, ``-(L P)`` at the coordinate (``P = dv/du``);
    - against ``computeMomentArm`` with the constraint (for the coordinates the loop moves): MomentArmSolver projects the coordinate's unit
      speed onto the loop's velocity constraint ``G u = 0`` (``projectU``, least squares with unit
      weights), divides it by the coordinate's projected speed, and returns that ``C`` times the
      generalized forces: ours ``C^T (-(L P))`` with ``C`` from our ``G``.

    1e-9 relative (floor 1 mm) without an ellipsoid, 1e-6 with one."""
    monkeypatch.chdir(tmp_path)
    tsm = Loaded(TSM, tmp_path)
    free = Loaded(TSM, tmp_path, enforce=False)
    assert tsm.ellipsoid.any() and not tsm.ellipsoid.all()
    worst = _check_paths(tsm, free, 30, np.random.default_rng(19))
    for kind in ("length", "arm", "constrained"):
        assert worst[kind, False] < 1e-9 and worst[kind, True] < 1e-6, worst


@pytest.mark.parametrize("tag,value,match", [("Flen", "0.9", "Flen"), ("Af", "0", "Af"),
                                             ("minimum_activation", "0.001", "minimum_activation")])
def test_thelen_refuses_bad_properties(tag, value, match):
    """A Thelen2003Muscle property OpenSim would refuse is refused, naming the muscle and the field."""
    from mcdm_pin.exceptions import ModelError
    from mcdm_pin.osim.muscles import read_muscle

    force = next(ET.parse(ARM26).getroot().iter("Thelen2003Muscle"))
    node = force.find(tag)
    if node is None:
        node = ET.SubElement(force, tag)
    node.text = value
    with pytest.raises(ModelError, match=rf"Thelen2003Muscle 'TRIlong'.*{match}"):
        read_muscle(force, "arm26.osim")
