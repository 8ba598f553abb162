"""The OpenSim skeleton loader (mcdm_pin.osim) against OpenSim 4.6 itself: body frames, velocities,
mass matrix and inverse dynamics at random states of arm26 and the thoracoscapular model, OpenSim's
functions, couplings, the scapulothoracic joint's speeds, and the acromioclavicular loop's
constrained dynamics. OpenSim loads copies of the models in a temporary folder, with its log file
off (it writes opensim.log where it loads a model)."""

from __future__ import annotations

import os
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin.exceptions import ModelError
from mcdm_pin.osim import functions, speeds
from mcdm_pin.osim.load import osim_skeleton

osim = pytest.importorskip("opensim", reason="the OpenSim reference needs: pip install opensim")

REPO = Path(__file__).resolve().parents[1]
ARM26 = REPO / "robots" / "opensim" / "arm26.osim"
TSM = REPO / "robots" / "opensim" / "TSM_subject_noWeight.osim"
TSM_2KG = REPO / "robots" / "opensim" / "TSM_subject_2kgWeight.osim"
MOTION = REPO / "robots" / "opensim" / "motions" / "abd01"  # the committed excerpt of RMR's ABD01
STATES = 30


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A temporary working folder for OpenSim for the whole module, its log file off."""
    old = os.getcwd()
    path = tmp_path_factory.mktemp("opensim")
    os.chdir(path)
    osim.Logger.removeFileSink()
    osim.Logger.setLevelString("error")
    yield path
    os.chdir(old)


class Reference:
    """An OpenSim model (a copy in the working folder) with its forces off, and the coordinate ->
    mobility (u) slot map."""

    def __init__(self, path):
        copy = Path.cwd() / Path(path).name
        if copy != Path(path):
            shutil.copyfile(path, copy)
        self.model = osim.Model(str(copy))
        for force in list(self.model.getForceSet()):
            force.set_appliesForce(False)
        self.state = self.model.initSystem()
        self.coords = self.model.getCoordinateSet()
        self.n = self.coords.getSize()
        for i in range(self.n):
            self.coords.get(i).setSpeedValue(self.state, i + 1.0)
        u = np.array([self.state.getU().get(i) for i in range(self.state.getNU())])
        self.slot = [int(np.flatnonzero(u == i + 1.0)[0]) for i in range(self.n)]

    def set(self, x, u=None):
        for i in range(self.n):
            self.coords.get(i).setValue(self.state, float(x[i]), False)
            self.coords.get(i).setSpeedValue(self.state, 0.0 if u is None else float(u[i]))
        self.model.realizeVelocity(self.state)

    def mass_matrix(self):
        M = osim.Matrix()
        self.model.getMatterSubsystem().calcM(self.state, M)
        full = np.array([[M.get(i, j) for j in range(M.ncol())] for i in range(M.nrow())])
        return full[np.ix_(self.slot, self.slot)]

    def inverse_dynamics(self, udot):
        vec = osim.Vector(self.n, 0.0)
        for i in range(self.n):
            vec.set(self.slot[i], float(udot[i]))
        tau = osim.InverseDynamicsSolver(self.model).solve(self.state, vec)
        return np.array([tau.get(self.slot[i]) for i in range(self.n)])


def _vec3(v):
    return np.array([v.get(i) for i in range(3)])


def _pin_state(om, x, u=None, udot=None):
    """Pinocchio (q, v, a) of OpenSim coordinates, speeds and their rates (file order)."""
    cv = om.coordinate_v
    q = np.zeros(om.model.nq)
    q[om.q_index[cv]] = x
    if u is None:
        return q
    U, A = np.zeros(om.model.nv), np.zeros(om.model.nv)
    U[cv], A[cv] = u, (np.zeros(len(cv)) if udot is None else udot)
    v, a = speeds.from_speeds(om.angular, q, U, A)
    return q, v, a


def _speed_jacobian(om, q):
    """P = dv/du (nv, nv) at q (the map is linear in u)."""
    return np.column_stack([speeds.from_speeds(om.angular, q, e) for e in np.eye(om.model.nv)])


@pytest.fixture(scope="module")
def chain(workdir):
    """A chain of one body per OpenSim joint type (FreeJoint at the root, then Pin, Slider, Universal,
    Gimbal, Ball, Weld, Pin), random offsets, orientations and inertias, written by OpenSim itself."""
    rng = np.random.default_rng(10)

    def vec(x):
        return osim.Vec3(*[float(t) for t in x])

    model = osim.Model()
    model.setName("chain")
    parent = model.getGround()
    for k, kind in enumerate(["FreeJoint", "PinJoint", "SliderJoint", "UniversalJoint", "GimbalJoint", "BallJoint",
                              "WeldJoint", "PinJoint"]):
        inertia = [*(0.02 + 0.01 * rng.random(3)), *(0.001 * rng.normal(size=3))]
        body = osim.Body(f"b{k}", float(rng.uniform(0.5, 2.0)), vec(0.1 * rng.normal(size=3)),
                         osim.Inertia(*[float(t) for t in inertia]))
        model.addBody(body)
        model.addJoint(getattr(osim, kind)(f"j{k}", parent, vec(0.2 * rng.normal(size=3)), vec(rng.normal(size=3)),
                                           body, vec(0.2 * rng.normal(size=3)), vec(rng.normal(size=3))))
        parent = body
    model.finalizeConnections()
    path = workdir / "chain.osim"
    model.printToXML(str(path))
    return path


def test_every_joint_type_matches_opensim(workdir, chain):
    om, _, _, _ = osim_skeleton(chain)
    assert [om.model.joints[j].shortname() for j in range(1, om.model.njoints)] == [
        "JointModelComposite", "JointModelRZ", "JointModelPX", "JointModelComposite", "JointModelComposite",
        "JointModelComposite", "JointModelRZ"]
    test_body_frames_and_velocities_match_opensim(workdir, chain)
    test_mass_matrix_and_inverse_dynamics_match_opensim(workdir, chain)


@pytest.mark.parametrize("path", [ARM26, TSM], ids=["arm26", "tsm"])
def test_body_frames_and_velocities_match_opensim(workdir, path):
    om, _, _, _ = osim_skeleton(path)
    ref = Reference(path)
    data = om.model.createData()
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(STATES):
        x, u = rng.uniform(-1.2, 1.2, ref.n), rng.normal(size=ref.n)
        ref.set(x, u)
        q, v, _ = _pin_state(om, x, u)
        pin.forwardKinematics(om.model, data, q, v)
        pin.updateFramePlacements(om.model, data)
        for body in list(ref.model.getBodySet()):
            fid = om.model.getFrameId(body.getName())
            assert om.model.frames[fid].name == body.getName()
            T = body.getTransformInGround(ref.state)
            R = np.array([[T.R().get(i, j) for j in range(3)] for i in range(3)])
            V = body.getVelocityInGround(ref.state)
            mine = pin.getFrameVelocity(om.model, data, fid, pin.LOCAL_WORLD_ALIGNED)
            worst = max(worst, np.abs(data.oMf[fid].translation - _vec3(T.p())).max(),
                        np.abs(data.oMf[fid].rotation - R).max(),
                        np.abs(mine.angular - _vec3(V.get(0))).max(), np.abs(mine.linear - _vec3(V.get(1))).max())
        for marker in list(ref.model.getMarkerSet()):  # markers: OP_FRAMEs named by their path
            fid = om.model.getFrameId(f"/markerset/{marker.getName()}")
            worst = max(worst, np.abs(data.oMf[fid].translation - _vec3(marker.getLocationInGround(ref.state))).max())
    assert worst < 1e-12


@pytest.mark.parametrize("path", [ARM26, TSM, TSM_2KG], ids=["arm26", "tsm", "tsm-2kg"])
def test_mass_matrix_and_inverse_dynamics_match_opensim(workdir, path):
    om, _, _, _ = osim_skeleton(path)
    ref = Reference(path)
    data = om.model.createData()
    rng = np.random.default_rng(2)
    cv = om.coordinate_v
    err_M = err_tau = 0.0
    for _ in range(STATES):
        x, u, udot = rng.uniform(-1.2, 1.2, ref.n), rng.normal(size=ref.n), rng.normal(size=ref.n)
        ref.set(x, u)
        q, v, a = _pin_state(om, x, u, udot)
        P = _speed_jacobian(om, q)
        M = pin.crba(om.model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        M_u = (P.T @ M @ P)[np.ix_(cv, cv)]  # OpenSim's M is in its speeds u
        tau_u = (P.T @ pin.rnea(om.model, data, q, v, a))[cv]
        M_ref, tau_ref = ref.mass_matrix(), ref.inverse_dynamics(udot)
        err_M = max(err_M, np.abs(M_u - M_ref).max() / np.abs(M_ref).max())
        err_tau = max(err_tau, np.abs(tau_u - tau_ref).max() / max(1.0, np.abs(tau_ref).max()))
    assert err_M < 1e-9 and err_tau < 1e-9


def test_scapulothoracic_speeds_are_an_angular_velocity(workdir):
    """OpenSim's ellipsoid speeds are not the angle rates: u = E v (mcdm_pin.osim.speeds), and the
    maps invert each other, velocities and accelerations."""
    om, _, src, _ = osim_skeleton(TSM)
    (idx,) = om.angular
    rng = np.random.default_rng(3)
    for _ in range(STATES):
        q = _pin_state(om, rng.uniform(-1.2, 1.2, len(om.coordinates)))
        v, a = rng.normal(size=om.model.nv), rng.normal(size=om.model.nv)
        u = speeds.to_speeds(om.angular, q, v)
        assert not np.allclose(u[list(idx)], v[list(idx)])
        # udot by central differences along the motion
        h = 1e-6
        up = speeds.to_speeds(om.angular, pin.integrate(om.model, q, h * v), v + h * a)
        um = speeds.to_speeds(om.angular, pin.integrate(om.model, q, -h * v), v - h * a)
        v2, a2 = speeds.from_speeds(om.angular, q, u, (up - um) / (2 * h))
        assert np.allclose(v2, v, atol=1e-12) and np.allclose(a2, a, atol=1e-7)
        tau = rng.normal(size=om.model.nv)
        assert np.allclose(speeds.forces_to_osim(om.angular, q, speeds.forces_to_pin(om.angular, q, tau)), tau)
        assert np.isclose(speeds.forces_to_pin(om.angular, q, tau) @ v, tau @ u)  # power


def test_coordinates_round_trip():
    om, _, src, _ = osim_skeleton(TSM)
    rng = np.random.default_rng(4)
    for _ in range(STATES):
        values = dict(zip(om.coordinates, rng.uniform(-1.2, 1.2, len(om.coordinates))))
        q = src.configuration(values)
        assert src.coordinate_values(q) == pytest.approx(values, abs=0, rel=0)
        sp = dict(zip(om.coordinates, rng.normal(size=len(om.coordinates))))
        v = src.velocity(q, sp)
        assert src.speeds(q, v) == pytest.approx(sp, abs=1e-12)
    assert src.coordinate_values(src.configuration({})) == dict(zip(om.coordinates, om.defaults))


@pytest.mark.parametrize("tag", ["SimmSpline", "PiecewiseLinearFunction"])
def test_functions_match_opensim(tag):
    rng = np.random.default_rng(5)
    for n in (2, 3, 4, 9):
        x, y = np.sort(rng.uniform(-2, 2, n)), rng.normal(size=n)
        ref = getattr(osim, tag)()
        for a, b in zip(x, y):
            ref.addPoint(float(a), float(b))
        mine = {"SimmSpline": functions.simm_spline, "PiecewiseLinearFunction": functions.piecewise_linear}[tag](x, y)
        for t in np.concatenate([rng.uniform(x[0], x[-1], 25), [x[0] - 0.3, x[-1] + 0.4]]):
            arg = osim.Vector(1, float(t))
            want = (ref.calcValue(arg), ref.calcDerivative(osim.StdVectorInt([0]), arg),
                    ref.calcDerivative(osim.StdVectorInt([0, 0]), arg))
            assert np.allclose(mine.value(t), want, rtol=0, atol=1e-12)


def test_polynomial_matches_opensim():
    coef = [0.3, -1.2, 0.5, 2.0]  # highest power first, as OpenSim's PolynomialFunction
    vec = osim.Vector(len(coef), 0.0)
    for i, c in enumerate(coef):
        vec.set(i, c)
    ref = osim.PolynomialFunction(vec)
    for t in np.linspace(-2.0, 2.0, 9):
        arg = osim.Vector(1, float(t))
        want = (ref.calcValue(arg), ref.calcDerivative(osim.StdVectorInt([0]), arg),
                ref.calcDerivative(osim.StdVectorInt([0, 0]), arg))
        assert np.allclose(functions.Polynomial(tuple(coef)).value(t), want, rtol=0, atol=1e-12)


# ------------------------------------------------------------------------------ couplings (a modified arm26)
def _coupled_arm26(tmp_path) -> Path:
    """arm26 whose elbow also translates along splines of the elbow angle (SimmSpline,
    NaturalCubicSpline, PiecewiseLinearFunction) and whose elbow angle follows the shoulder angle
    through a CoordinateCouplerConstraint."""
    tree = ET.parse(ARM26)
    model = tree.getroot().find("Model")
    elbow = next(j for j in model.find("JointSet").find("objects") if j.get("name") == "r_elbow")
    knots = np.linspace(0.0, 2.5, 6)
    for k, tag in enumerate(("SimmSpline", "NaturalCubicSpline", "PiecewiseLinearFunction")):
        axis = next(a for a in elbow.find("SpatialTransform") if a.get("name") == f"translation{k + 1}")
        axis.find("coordinates").text = "r_elbow_flex"
        for child in [c for c in axis if c.tag not in ("coordinates", "axis")]:
            axis.remove(child)
        f = ET.SubElement(axis, tag, name="function")
        ET.SubElement(f, "x").text = " ".join(map(repr, knots.tolist()))
        ET.SubElement(f, "y").text = " ".join(map(repr, (0.01 * np.sin(knots * (k + 1))).tolist()))
    cset = model.find("ConstraintSet")
    objects = cset.find("objects")
    if objects is None:
        objects = ET.SubElement(cset, "objects")
    c = ET.SubElement(objects, "CoordinateCouplerConstraint", name="elbow_follows_shoulder")
    ET.SubElement(c, "isEnforced").text = "true"
    ET.SubElement(c, "independent_coordinate_names").text = "r_shoulder_elev"
    ET.SubElement(c, "dependent_coordinate_name").text = "r_elbow_flex"
    holder = ET.SubElement(c, "coupled_coordinates_function")
    lin = ET.SubElement(holder, "LinearFunction", name="function")
    ET.SubElement(lin, "coefficients").text = "0.5 0.8"
    out = tmp_path / "arm26_coupled.osim"
    tree.write(out)
    return out


def test_couplings_follow_opensim(workdir, tmp_path):
    path = _coupled_arm26(tmp_path)
    om, couplings, src, _ = osim_skeleton(path)
    assert len(couplings) == 4 and om.model.nv == 5
    assert set(om.velocity_names) >= {"r_elbow/translation1", "r_elbow/translation2", "r_elbow/translation3"}
    ref = Reference(path)
    data = om.model.createData()
    rng = np.random.default_rng(6)
    worst = 0.0
    for _ in range(STATES):
        shoulder, rate = rng.uniform(-0.5, 2.0), rng.normal()
        q = src.configuration({"r_shoulder_elev": shoulder})  # the elbow and translations filled
        elbow = 0.5 * shoulder + 0.8
        assert src.coordinate_values(q)["r_elbow_flex"] == pytest.approx(elbow, abs=1e-15)
        v = src.velocity(q, {"r_shoulder_elev": rate, "r_elbow_flex": 0.5 * rate})
        couplings.check(q, v)
        ref.set([shoulder, elbow], [rate, 0.5 * rate])
        pin.forwardKinematics(om.model, data, q, v)
        pin.updateFramePlacements(om.model, data)
        for body in list(ref.model.getBodySet()):
            fid = om.model.getFrameId(body.getName())
            T, V = body.getTransformInGround(ref.state), body.getVelocityInGround(ref.state)
            mine = pin.getFrameVelocity(om.model, data, fid, pin.LOCAL_WORLD_ALIGNED)
            worst = max(worst, np.abs(data.oMf[fid].translation - _vec3(T.p())).max(),
                        np.abs(mine.linear - _vec3(V.get(1))).max())
    assert worst < 1e-12
    with pytest.raises(Exception, match="elbow_follows_shoulder"):
        src.configuration({"r_shoulder_elev": 0.3, "r_elbow_flex": 0.0})


def test_function_couplings_basis_and_rates_equal_finite_differences(tmp_path):
    """N = dq/dz and the filled velocities and accelerations of spline couplings (the chain rule with
    f' and f'') against central differences of the coupled map."""
    om, couplings, src, _ = osim_skeleton(_coupled_arm26(tmp_path))
    rng = np.random.default_rng(11)
    (z_index,) = couplings.independent
    for _ in range(10):
        z, zd, zdd = rng.uniform(-0.5, 2.0), rng.normal(), rng.normal()
        q = src.configuration({"r_shoulder_elev": z})
        h = 1e-5

        def at(t):
            return src.configuration({"r_shoulder_elev": t})

        N = couplings.basis(q)
        assert np.allclose(N[:, 0], (at(z + h) - at(z - h)) / (2 * h), rtol=0, atol=1e-8)
        v0, a0 = np.zeros(om.model.nv), np.zeros(om.model.nv)
        v0[z_index], a0[z_index] = zd, zdd
        _, v, a = couplings.fill(q, v0, a0)
        # q(t) = map(z + zd t + zdd t^2 / 2): v = dq/dt, a = d2q/dt2 at t = 0
        path = lambda t: at(z + zd * t + 0.5 * zdd * t * t)
        assert np.allclose(v, (path(h) - path(-h)) / (2 * h), rtol=0, atol=1e-8)
        assert np.allclose(a, (path(h) - 2 * path(0.0) + path(-h)) / h ** 2, rtol=0, atol=1e-4)


# ------------------------------------------------------------------------------------ the AC loop
def test_point_constraint_loop_matches_opensim_constrained_dynamics(workdir):
    """On states on the loop, the projected equation (N K)^T (M a + h - tau) = 0 with G a + gamma = 0
    gives OpenSim's constrained accelerations (SimbodyMatterSubsystem.calcAcceleration, gravity and
    forces off), and the recovered loop force closes the full equation and RNEA with it as fext."""
    om, _, src, _ = osim_skeleton(TSM)
    loops = src.loops
    model = om.model.copy()
    model.gravity = pin.Motion.Zero()
    data = model.createData()
    ref = Reference(TSM)
    matter = ref.model.getMatterSubsystem()
    rng = np.random.default_rng(7)
    cv = om.coordinate_v
    worst_a = worst_eq = worst_loop = 0.0
    for _ in range(STATES):
        q = loops.project(src.configuration({}) + rng.uniform(-0.2, 0.2, model.nq))
        K = loops.basis(q)
        v = K @ rng.normal(size=K.shape[1])
        worst_loop = max(worst_loop, np.abs(loops.residual(q)).max(), np.abs(loops.velocity_residual(q, v)).max())
        u = speeds.to_speeds(om.angular, q, v)[cv]
        tau_u = rng.normal(size=len(cv))
        ref.set(q[om.q_index[cv]], u)
        mob = osim.Vector(len(cv), 0.0)
        for i in range(len(cv)):
            mob.set(ref.slot[i], float(tau_u[i]))
        udot, acc = osim.Vector(), osim.VectorOfSpatialVec()
        bodies = osim.VectorOfSpatialVec(10, osim.SpatialVec(osim.Vec3(0), osim.Vec3(0)))  # Simbody's bodies
        matter.calcAcceleration(ref.state, mob, bodies, udot, acc)
        U, Udot = np.zeros(model.nv), np.zeros(model.nv)
        U[cv], Udot[cv] = u, [udot.get(ref.slot[i]) for i in range(len(cv))]
        _, a_ref = speeds.from_speeds(om.angular, q, U, Udot)
        tau = np.zeros(model.nv)
        tau[cv] = tau_u
        tau = speeds.forces_to_pin(om.angular, q, tau)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        h = pin.rnea(model, data, q, v, np.zeros(model.nv))
        G = loops.jacobian(q)
        a = np.linalg.solve(np.vstack([K.T @ M, G]), np.concatenate([K.T @ (tau - h), -loops.bias(q, v)]))
        worst_a = max(worst_a, np.abs(a - a_ref).max() / np.abs(a_ref).max())
        lam = loops.force(q, M @ a + h - tau)
        with_loop = pin.rnea(model, data, q, v, a, loops.external_forces(q, lam)) - tau
        worst_eq = max(worst_eq, np.abs(M @ a + h - tau - G.T @ lam).max(), np.abs(with_loop).max())
    assert worst_loop < 1e-12
    assert worst_a < 1e-9
    assert worst_eq < 1e-9


def test_loop_force_and_wrench_maps_are_affine_in_the_cable_forces():
    """lambda = lambda_0 + Lambda f equals force(q, M a + h + L^T f), and W lambda is what the loop
    force adds to every joint's RNEA wrench."""
    om, _, src, _ = osim_skeleton(TSM)
    model, data, loops = om.model, om.model.createData(), src.loops
    rng = np.random.default_rng(9)
    for _ in range(5):
        q = loops.project(src.configuration({}) + rng.uniform(-0.2, 0.2, model.nq))
        v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)
        L, f = rng.normal(size=(4, model.nv)), rng.uniform(0, 50, 4)
        tau0 = pin.rnea(model, data, q, v, a)
        lam0, Lam = loops.force_map(q, tau0, L)
        lam = loops.force(q, tau0 + L.T @ f)
        assert np.allclose(lam0 + Lam @ f, lam, rtol=0, atol=1e-9)
        before = [data.f[j].vector.copy() for j in range(model.njoints)]
        pin.rnea(model, data, q, v, a, loops.external_forces(q, lam))
        W = loops.wrench_map(q)
        for j in range(1, model.njoints):
            assert np.allclose(data.f[j].vector - before[j], W[j] @ lam, rtol=0, atol=1e-9)


def test_loop_instant_equals_its_separate_maps():
    """PointLoops.instant (one Jacobian pass, one SVD) gives basis, force_map (cables and actuators)
    and wrench_map's numbers; its basis spans the null space of G; and PointLoops.terms adds them to
    an instant's terms as numpy does."""
    om, _, src, _ = osim_skeleton(TSM)
    model, loops = om.model, src.loops
    rng = np.random.default_rng(4)
    q = loops.project(src.configuration({}) + rng.uniform(-0.2, 0.2, model.nq))
    tau0, L, S = rng.normal(size=model.nv), rng.normal(size=(4, model.nv)), rng.normal(size=(model.nv, 2))
    basis, lam0, Lam, Lam_act, W = loops.instant(q, tau0, L, S)
    G, d = loops.jacobian(q), model.createData()  # G from data.J (one kernel) equals Pinocchio's frame Jacobians
    pin.computeJointJacobians(model, d, q)
    pin.updateFramePlacements(model, d)
    ref_G = np.vstack([pin.getFrameJacobian(model, d, b, pin.LOCAL_WORLD_ALIGNED)[:3]
                       - pin.getFrameJacobian(model, d, a, pin.LOCAL_WORLD_ALIGNED)[:3] for _, a, b in loops.loops])
    assert np.allclose(G, ref_G, rtol=0, atol=1e-15)
    ref_basis = loops.basis(q)
    assert np.abs(loops.jacobian(q) @ basis).max() < 1e-12
    assert np.allclose(basis @ basis.T, ref_basis @ ref_basis.T, rtol=0, atol=1e-12)  # same subspace
    ref0, ref = loops.force_map(q, tau0, L)
    assert np.allclose(lam0, ref0, rtol=1e-12, atol=1e-12) and np.allclose(Lam, ref, rtol=1e-12, atol=1e-12)
    assert np.allclose(Lam_act, loops.force_map(q, np.zeros(model.nv), -S.T)[1], rtol=1e-12, atol=1e-12)
    assert np.array_equal(W, loops.wrench_map(q))
    # what the maps add to an instant's terms (PointLoops.terms, one compiled call) is the numpy of them
    child = np.array([j for j in range(1, model.njoints) if W[j].any()] + [1], dtype=np.int64)
    u, RT = rng.normal(size=(len(child), 6)), rng.normal(size=(len(child), 6, L.shape[0]))
    out = loops.terms(q, tau0, L, S, u, RT, child)
    Wc = W[child]
    for got, want in ((out.basis, basis), (out.u, u + Wc @ lam0), (out.RT, RT + Wc @ Lam),
                      (out.RT_act, Wc @ Lam_act), (out.actuation, basis.T @ S), (out.L, L @ basis),
                      (out.tau, basis.T @ tau0)):
        assert got.shape == want.shape and np.allclose(got, want, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("path", [ARM26, TSM], ids=["arm26", "tsm"])
def test_interaction_wrenches_equal_opensims_joint_reactions(workdir, path):
    """With OpenSim's forward dynamics (gravity, forces off) giving the accelerations, RNEA's
    ``data.f`` (with the loop force as fext on the TSM) is OpenSim's reaction on each joint's child
    frame (``calcReactionOnChildExpressedInGround``): the physical joints' interaction wrenches sit
    at OpenSim's child frames and the loop force acts in them."""
    om, _, src, _ = osim_skeleton(path)
    model, ref = om.model, Reference(path)
    data = model.createData()
    rng = np.random.default_rng(8)
    cv = om.coordinate_v
    worst = worst_tau = 0.0
    for _ in range(STATES):
        if src.loops is None:
            q, v = src.configuration({}) + rng.uniform(-1.0, 1.0, model.nq), rng.normal(size=model.nv)
        else:
            q = src.loops.project(src.configuration({}) + rng.uniform(-0.2, 0.2, model.nq))
            v = src.loops.basis(q) @ rng.normal(size=model.nv - 3)
        u = speeds.to_speeds(om.angular, q, v)[cv]
        ref.set(q[om.q_index[cv]], u)
        ref.model.realizeAcceleration(ref.state)
        U, Udot = np.zeros(model.nv), np.zeros(model.nv)
        U[cv], Udot[cv] = u, [ref.state.getUDot().get(ref.slot[i]) for i in range(len(cv))]
        _, a = speeds.from_speeds(om.angular, q, U, Udot)
        fext = None
        if src.loops is not None:
            M = pin.crba(model, data, q)
            M = np.triu(M) + np.triu(M, 1).T
            fext = src.loops.external_forces(q, src.loops.force(q, M @ a + pin.rnea(model, data, q, v, 0 * a)))
        tau = pin.rnea(model, data, q, v, a) if fext is None else pin.rnea(model, data, q, v, a, fext)
        worst_tau = max(worst_tau, np.abs(tau).max())
        pin.forwardKinematics(model, data, q)
        for j in range(1, model.njoints):
            joint = ref.model.getJointSet().get(model.names[j])
            child = joint.getChildFrame().getTransformInGround(ref.state)
            assert np.allclose(data.oMi[j].translation, _vec3(child.p()), rtol=0, atol=1e-12)
            reaction = joint.calcReactionOnChildExpressedInGround(ref.state)
            R = data.oMi[j].rotation
            worst = max(worst, np.abs(R @ data.f[j].angular - _vec3(reaction.get(0))).max(),
                        np.abs(R @ data.f[j].linear - _vec3(reaction.get(1))).max())
    assert worst_tau < 1e-9  # no actuation: the equation of motion closes with the loop force alone
    assert worst < 1e-9


def test_measured_motions_lie_on_the_loop():
    """ABD01 as CMC tracked it (the committed excerpt) lies on the acromioclavicular loop."""
    om, _, src, _ = osim_skeleton(TSM)

    def sto(path):
        lines = path.read_text().splitlines()
        k = lines.index("endheader")
        return lines[k + 1].split("\t")[1:], np.loadtxt(lines[k + 2:])[:, 1:]

    names, Q = sto(MOTION / "Kinematics_q.sto")
    _, U = sto(MOTION / "Kinematics_u.sto")
    scale = np.array([1.0 if n.endswith(("_tx", "_ty", "_tz")) else np.pi / 180 for n in names])
    for k in range(0, len(Q), 20):
        q = src.configuration(dict(zip(names, Q[k] * scale)))
        v = src.velocity(q, dict(zip(names, U[k] * scale)))
        assert np.abs(src.loops.residual(q)).max() < 1e-7
        assert np.abs(src.loops.velocity_residual(q, v)).max() < 1e-7


# ------------------------------------------------------------------------------------ refusals, Robot
def _edited(tmp_path, replacements) -> Path:
    """arm26 with each ``(old, new)`` replaced once (the last occurrence when ``old`` starts with '$')."""
    text = ARM26.read_text()
    for old, new in replacements:
        last = old.startswith("$")
        old = old.lstrip("$")
        assert old in text
        k = text.rindex(old) if last else text.index(old)
        text = text[:k] + new + text[k + len(old):]
    out = tmp_path / "edited.osim"
    out.write_text(text)
    return out


@pytest.mark.parametrize("replacements,match", [
    ([('<CustomJoint name="r_elbow">', '<PlanarJoint name="r_elbow">'), ("$</CustomJoint>", "</PlanarJoint>")],
     r"PlanarJoint 'r_elbow'.*not supported.*\(line \d+\)"),
    ([('Version="40000"', 'Version="30000"')], "before OpenSim 4"),
    ([("<prescribed_function />", "<prescribed_function><Constant><value>1</value></Constant></prescribed_function>"
                                   "<prescribed>true</prescribed>")], "r_shoulder_elev.*prescribed"),
    ([("<coefficients> 1 0</coefficients>", "<coefficients> 2 0</coefficients>")], r"r_shoulder.*f\(x\) = x"),
    ([("<mass>", "<mass>-1")], r"Body 'base': <mass> must be finite and >= 0.*\(line \d+\)"),
], ids=["unknown joint", "OpenSim 3", "prescribed", "no identity axis", "negative mass"])
def test_refusals_name_the_element(tmp_path, replacements, match):
    with pytest.raises(ModelError, match=match):
        osim_skeleton(_edited(tmp_path, replacements))


def test_robot_load_speaks_opensim_names():
    """Robot.load reads the muscles (cables named after them) and the CoordinateActuators (actuators
    labelled with their names, on their coordinates)."""
    from mcdm_pin import Robot

    robot = Robot.load(TSM)
    assert robot.joint_names == ("ground_thorax", "sternoclavicular", "scapulothoracic", "GlenoHumeral", "elbow",
                                 "radioulnar")
    assert set(robot.link_names) == {"ground", "thorax", "clavicle", "scapula", "humerus", "ulna", "radius", "hand"}
    assert set(robot.coordinate_names) == set(robot.source.maps.coordinates)
    q = robot.configuration({"shoulder_elv": 0.7, "scapula_winging": 0.1})
    assert robot.source.coordinate_values(q)["shoulder_elv"] == 0.7
    assert q[robot.coordinate_names.index("scapula_winging")] == 0.1
    assert any("PointConstraint 'AC'" in note for note in robot.notes)
    assert robot.m == 33 and robot.cable_names[0] == "TrapeziusScapula_M" and robot.cables.muscles is not None
    assert robot.n_act == 17 and robot.actuators[4].label == "ground_thorax_ty_actuator"
    assert robot.actuators[4].tau_max[0] == 500.0 * 1e4  # optimal_force 500, control range capped at 1e4
    assert robot.coordinate_names[int(robot.actuators[4].idx_v[0])] == "ground_thorax_ty"
    assert not any("not a path force" in note for note in robot.notes)


def test_a_locked_coordinate_is_fixed_at_its_default(tmp_path):
    path = _edited(tmp_path, [("<locked>false</locked>", "<locked>true</locked>")])  # r_shoulder_elev
    om, couplings, src, _ = osim_skeleton(path)
    default = om.defaults[om.coordinates.index("r_shoulder_elev")]
    assert couplings.n == 1 and couplings.independent_names == ("r_elbow_flex",)
    q = src.configuration({"r_elbow_flex": 0.4})
    assert src.coordinate_values(q) == {"r_shoulder_elev": default, "r_elbow_flex": 0.4}
    assert np.allclose(couplings.basis(q), [[0.0], [1.0]])
    with pytest.raises(Exception, match="r_shoulder_elev"):
        src.configuration({"r_shoulder_elev": default + 0.1})


def test_the_default_pose_is_moved_onto_the_loop_by_the_shoulder_girdle_only():
    om, _, src, _ = osim_skeleton(TSM)
    q = src.configuration({})
    assert np.abs(src.loops.residual(q)).max() > 1e-3  # the file's defaults are off the loop (OpenSim assembles)
    girdle = [om.velocity_names.index(n) for n in ("clav_prot", "clav_elev", "scapula_abduction",
                                                   "scapula_elevation", "scapula_upward_rot", "scapula_winging")]
    on = src.loops.project(q, free=girdle)
    assert np.abs(src.loops.residual(on)).max() < 1e-12
    others = [i for i in range(om.model.nv) if i not in girdle]
    assert np.array_equal(on[others], q[others])
