"""A sidecar over an MJCF file (``mjcf:``): MuJoCo compiles the file once and the robot is built once,
with the sidecar's joint settings and reserves; the result equals the MJCF file's robot otherwise."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("mujoco")

import mcdm_pin.robot as robot_module  # noqa: E402
from mcdm_pin import Robot, SidecarError  # noqa: E402

ARM = Path(__file__).resolve().parents[1] / "robots" / "myosuite" / "myoarm.yaml"


def test_myoarm_sidecar_compiles_and_builds_once(monkeypatch):
    counts = {"compile": 0, "robot": 0}
    compile_mjcf, init = robot_module.compile_mjcf, Robot.__init__

    def counted_compile(path):
        counts["compile"] += 1
        return compile_mjcf(path)

    def counted_init(self, *args, **kwargs):
        counts["robot"] += 1
        init(self, *args, **kwargs)

    monkeypatch.setattr(robot_module, "compile_mjcf", counted_compile)
    monkeypatch.setattr(Robot, "__init__", counted_init)
    arm = Robot.load(ARM)
    assert counts == {"compile": 1, "robot": 1}
    monkeypatch.undo()
    plain = Robot.load(arm.sidecar.mjcf_path)
    # the sidecar changes joint settings and adds reserves, nothing else
    assert arm.name == "myoarm" and arm.sidecar is not None
    assert arm.coordinate_names == plain.coordinate_names and arm.cables.names == plain.cables.names
    assert len(arm.couplings) == len(plain.couplings) == 11
    masses = [i.mass for i in arm.model.inertias]
    assert masses == [i.mass for i in plain.model.inertias]
    assert len(plain.actuators) == 0 and len(arm.actuators) == 22
    assert [a.label for a in arm.actuators][:2] == ["deviation_r", "flexion_r"]
    assert np.all([a.tau_max[0] == 1.0 and a.weight == 100.0 for a in arm.actuators])
    gh = next(j for j in arm.joints if j.name == "scapphant_r")
    assert gh.cone_deg == pytest.approx(19.03, abs=1e-12)
    assert np.allclose(gh.socket_axis, [0.581488, 0.106335, 0.806576], atol=1e-6)


def test_reserve_on_a_coupled_coordinate_is_refused(tmp_path):
    data = yaml.safe_load(ARM.read_text())
    data["mjcf"] = str(ARM.parent / data["mjcf"])
    plain = Robot.load(data["mjcf"])
    dependent = plain.coordinate_names[int(plain.couplings.dependent[0])]
    data["reserves"] = [{"coordinates": [plain.couplings.independent_names[0], dependent], "max": 1.0, "weight": 1.0}]
    path = tmp_path / "arm.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    with pytest.raises(SidecarError, match=rf"reserves\[0\]\.coordinates\[1\].*{dependent}.*follows couplings"):
        Robot.load(path)
