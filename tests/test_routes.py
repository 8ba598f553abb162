"""Configuration-dependent routes on a URDF robot (sidecar wraps and pulleys): lengths against the
path's own geometry, ``L`` against finite differences, and the interaction wrenches against
Pinocchio's RNEA with the cable's forces applied at every point of its path (tangent points on the
wrap's body included), compiled and uncompiled."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin import yaml12
from mcdm_pin.exceptions import ModelError, SidecarError
from mcdm_pin.model.terms import TermsEvaluator
from mcdm_pin.robot import Robot
from mcdm_pin.sidecar import parse_sidecar

from .fd import lengths_jacobian

ROOT = Path(__file__).resolve().parents[1]
RNG = np.random.default_rng(7)


def wrapped_robot():
    """The paper's 2-link arm with three more cables: over a cylinder on link 1 (side point given),
    over a sphere at the elbow, and a two-branch cable over a pulley."""
    path = ROOT / "robots" / "two_link_sr.yaml"
    data = yaml12.load(path.read_text())
    data["cables"] += [
        {"name": "over_cylinder", "f_min": 0.0, "f_max": 500.0, "route": [
            {"link": "base", "point": [0.25, 0.0, 0.05]},
            {"wrap": "cylinder", "link": "link1", "radius": 0.04, "center": [0.0, 0.0, 0.1],
             "axis": [0.0, 1.0, 0.0], "side": [-0.2, 0.0, 0.1]},
            {"link": "link2", "point": [0.06, 0.0, 0.12]}]},
        {"name": "over_sphere", "f_min": 0.0, "f_max": 500.0, "route": [
            {"link": "link1", "point": [0.0, 0.06, 0.05]},
            {"wrap": "sphere", "link": "link1", "radius": 0.03, "center": [0.0, 0.0, 0.2]},
            {"link": "link2", "point": [0.0, 0.05, 0.1]}]},
        {"name": "pulley", "f_min": 0.0, "f_max": 500.0, "route": [
            {"link": "base", "point": [-0.2, 0.0, 0.0]},
            {"link": "link1", "point": [-0.05, 0.0, 0.15]},
            {"pulley": 2.0},
            {"link": "base", "point": [-0.2, 0.1, 0.0]},
            {"link": "link2", "point": [-0.05, 0.0, 0.1]}]},
    ]
    return Robot.from_sidecar(parse_sidecar(data, path=path))


@pytest.fixture(scope="module")
def robot():
    return wrapped_robot()


@pytest.mark.parametrize("compiled", [True, False])
def test_lengths_and_L_follow_the_path(robot, compiled):
    ev = TermsEvaluator(robot, compiled=compiled)
    engaged = np.zeros(len(robot.cables.wraps), dtype=int)
    for _ in range(25):
        q = RNG.uniform(-0.8, 0.8, robot.nv)
        t = ev(q)
        engaged += ev._routes.engaged
        L_fd = lengths_jacobian(lambda x: ev(x).lengths, q)
        assert np.abs(t.L - L_fd).max() < 1e-6 * max(1.0, np.abs(L_fd).max())
        # the pulley cable: the branch after the pulley counts 1/divisor (MuJoCo's rule)
        i = robot.cable_names.index("pulley")
        P = t.points[np.flatnonzero(robot.cables.point_cable == i)]
        expected = np.linalg.norm(P[1] - P[0]) + 0.5 * np.linalg.norm(P[3] - P[2])
        assert abs(t.lengths[i] - expected) < 1e-14
    assert engaged.min() > 0, "every wrap engaged at some sampled configuration"


def test_wrenches_equal_rnea_with_the_paths_point_forces(robot):
    ev = TermsEvaluator(robot)
    model = robot.model
    for _ in range(10):
        q, v, a = RNG.uniform(-0.8, 0.8, robot.nv), RNG.normal(size=robot.nv), RNG.normal(size=robot.nv)
        f = RNG.uniform(1.0, 50.0, robot.m)
        t = ev(q, v, a)
        routes = ev._routes
        oM = [ev.data.oMi[j] for j in range(model.njoints)]
        key_joint = np.array(ev._keys)
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        for s in np.flatnonzero(routes.seg_scale > 0):
            ia, ib = routes.seg_a[s], routes.seg_b[s]
            ja, jb = key_joint[routes.point_key[ia]], key_joint[routes.point_key[ib]]
            xa, xb = oM[ja].act(routes.point_local[ia]), oM[jb].act(routes.point_local[ib])
            u = (xb - xa) / np.linalg.norm(xb - xa)
            tension = f[routes.seg_cable[s]] * routes.seg_scale[s]
            for j, local, force in ((ja, routes.point_local[ia], tension * u), (jb, routes.point_local[ib], -tension * u)):
                R = oM[j].rotation
                fl = R.T @ force
                fext[j] += pin.Force(fl, np.cross(local, fl))
        data = model.createData()
        pin.rnea(model, data, q, v, a, fext)
        for k, joint in enumerate(robot.joints):
            ref = data.f[joint.child_id].vector
            assert np.abs(t.wrenches(f)[k] - ref).max() < 1e-9 * max(1.0, np.abs(ref).max())


def test_compiled_and_uncompiled_agree(robot):
    a, b = TermsEvaluator(robot, compiled=True), TermsEvaluator(robot, compiled=False)
    for _ in range(10):
        q = RNG.uniform(-0.8, 0.8, robot.nv)
        ta, tb = a(q), b(q)
        assert np.array_equal(ta.lengths, tb.lengths) or np.abs(ta.lengths - tb.lengths).max() < 1e-14
        assert np.abs(ta.RT - tb.RT).max() < 1e-12


def test_bad_wraps_are_refused_with_their_key():
    path = ROOT / "robots" / "two_link_sr.yaml"
    data = yaml12.load(path.read_text())
    data["cables"][0]["route"].insert(1, {"wrap": "cone", "link": "link1", "radius": 0.02})
    with pytest.raises(SidecarError, match=r"cables\[0\]\.route\[1\]\.wrap"):
        parse_sidecar(data, path=path)
    data["cables"][0]["route"][1] = {"wrap": "sphere", "link": "link1", "radius": 0.0}
    with pytest.raises(SidecarError, match=r"route\[1\]\.radius"):
        parse_sidecar(data, path=path)
    data["cables"][0]["route"] = [{"wrap": "sphere", "link": "link1", "radius": 0.02},
                                  {"link": "base", "point": [0, 0, 0]}, {"link": "link1", "point": [0, 0, 0.1]}]
    with pytest.raises((SidecarError, ModelError), match="between two route points"):
        Robot.from_sidecar(parse_sidecar(data, path=path))
