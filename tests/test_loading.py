"""Loading refuses what would be silently wrong: duplicate YAML keys, YAML 1.1 number forms, alias bombs,
huge numbers, URDF parser errors, unphysical inertias, zero axes, mimic joints, escaping package paths,
CSV rows lost as headers, inconsistent trajectories. Each case is one clear package error."""

from __future__ import annotations

import resource
import time

import numpy as np
import pytest

from mcdm_pin import Robot
from mcdm_pin.exceptions import ModelError, SidecarError, TrajectoryError
from mcdm_pin.trajectory import Trajectory, csv_trajectory, quintic_trajectory

from .conftest import TWO_LINK, TWO_LINK_URDF


def _sidecar(tmp_path, text: str, name: str = "robot.yaml"):
    (tmp_path / "arm.urdf").write_text(TWO_LINK_URDF.read_text())
    path = tmp_path / name
    path.write_text(text)
    return path


def _two_link_text(tmp_path) -> str:
    return TWO_LINK.read_text().replace("../urdf/two_link_sr.urdf", "arm.urdf")


def test_duplicate_keys_are_refused_naming_both_lines(tmp_path):
    text = _two_link_text(tmp_path)
    dup = text.replace("    f_max: 1000.0\n", "    f_max: 1000.0\n    f_max: 0.5\n", 1)
    with pytest.raises(SidecarError, match=r"duplicate key 'f_max' at line (\d+) \(first at line (\d+)\)") as err:
        Robot.load(_sidecar(tmp_path, dup))
    import re

    second, first = (int(x) for x in re.search(r"at line (\d+) \(first at line (\d+)\)", str(err.value)).groups())
    lines = dup.splitlines()
    assert "f_max: 1000.0" in lines[first - 1] and "f_max: 0.5" in lines[second - 1]
    twice = text + "\n" + text[text.index("cables:"):text.index("trajectories:")]
    with pytest.raises(SidecarError, match="duplicate key 'cables'"):
        Robot.load(_sidecar(tmp_path, twice))


def test_numbers_are_read_as_yaml_1_2(tmp_path):
    text = _two_link_text(tmp_path)
    with pytest.raises(SidecarError, match=r"cables\[0\].f_max: expected a number, got the string '1:30'"):
        Robot.load(_sidecar(tmp_path, text.replace("f_max: 1000.0", "f_max: 1:30", 1)))
    robot = Robot.load(_sidecar(tmp_path, text.replace("f_max: 1000.0", "f_max: 0100", 1)))
    assert robot.f_max[0] == 100.0  # YAML 1.1 read 0100 as octal 64
    robot = Robot.load(_sidecar(tmp_path, text.replace("f_max: 1000.0", "f_max: 1e3", 1)))
    assert robot.f_max[0] == 1000.0
    with pytest.raises(SidecarError, match=r"f_max: expected a number of magnitude at most 1e\+100, got an "
                                           r"integer of 400 digits"):
        Robot.load(_sidecar(tmp_path, text.replace("f_max: 1000.0", "f_max: " + "9" * 400, 1)))


def test_alias_bomb_is_refused_before_it_expands(tmp_path):
    bomb = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
        for p, c in zip("abcdefgh", "bcdefghi")) + "version: 1\n"
    assert len(bomb) < 400
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    with pytest.raises(SidecarError, match="expands to more than .* nodes through its aliases"):
        Robot.load(_sidecar(tmp_path, bomb))
    assert time.perf_counter() - start < 5.0
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 200_000  # kB


@pytest.mark.parametrize("edit, message", [
    (('<mass value="0.1"/>', '<mass value="abc"/>'), r"the URDF parser reported: Error: Inertial: mass \[abc\] is not a float"),
    (('ixx="1"', 'ixx="-1"'), "principal moments .* positive semidefinite"),
    (('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>'), r"joint 'q2_y': <axis xyz> is zero"),
    (('<joint name="q4_x" type="revolute">', '<joint name="q4_x" type="revolute"><mimic joint="q1_x"/>'),
     r"joint 'q4_x': <mimic> joints are not supported"),
])
def test_urdf_problems_are_fatal(tmp_path, edit, message):
    path = _sidecar(tmp_path, _two_link_text(tmp_path))
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(urdf.read_text().replace(*edit, 1))
    with pytest.raises(ModelError, match=message) as err:
        Robot.load(path)
    assert str(urdf) in str(err.value) and "\n" not in str(err.value)


def test_a_urdf_given_as_sidecar_says_what_it_is(tmp_path):
    with pytest.raises(SidecarError, match="this is a URDF, not a sidecar"):
        Robot.load(TWO_LINK_URDF)


def test_package_paths_stay_inside_their_package(tmp_path):
    text = _two_link_text(tmp_path).replace("urdf: arm.urdf", "urdf: package://example-robot-data/../../../etc/passwd")
    with pytest.raises(SidecarError, match="leaves the package 'example-robot-data'"):
        Robot.load(_sidecar(tmp_path, text))


def test_csv_first_row_is_data_or_a_header_of_names(two_link, tmp_path):
    rows = "".join(f"{t / 10},0.1,0,0,0\n" for t in range(8))
    path = tmp_path / "a.csv"
    path.write_text("0.0,0.1,0,0,x\n" + rows[rows.index("\n") + 1:])  # a typo in the first row
    with pytest.raises(TrajectoryError, match=r"row 1, column 5: expected a number, got 'x'"):
        csv_trajectory(two_link, path)
    path.write_bytes(b"\xef\xbb\xbf" + rows.encode())  # a byte-order mark: the first row is still data
    assert len(csv_trajectory(two_link, path)) == 8


def test_trajectory_sizes_must_agree():
    with pytest.raises(TrajectoryError, match="q has shape .* expected 3 rows"):
        Trajectory("x", np.arange(3.0), np.zeros((2, 4)), np.zeros((3, 4)), np.zeros((3, 4)))


def test_quintic_needs_a_finite_duration(two_link):
    for duration, dt in ((float("inf"), 0.01), (1.0, float("nan")), (1.0, 1e-9)):
        with pytest.raises(TrajectoryError):
            quintic_trajectory(two_link, np.zeros(4), np.ones(4), duration, dt)


def test_results_archive_sizes_are_checked_before_reading(tmp_path, monkeypatch):
    """A zip bomb: the archive's directory says how large its arrays unpack; beyond the limit nothing is
    read (the limit is lowered here so that the bomb stays small; the check is the same)."""
    import mcdm_pin.limits
    from mcdm_pin.exceptions import ResultsError
    from mcdm_pin.results import TrajectoryResult

    path = tmp_path / "bomb.npz"
    np.savez_compressed(path, t=np.zeros(200_000))  # 1.6 MB of zeros, a few kB on disk
    assert path.stat().st_size < 20_000
    monkeypatch.setattr(mcdm_pin.limits, "MAX_RESULTS_BYTES", 1_000_000)
    with pytest.raises(ResultsError, match=r"unpack to \d+ bytes; at most 1000000 are read"):
        TrajectoryResult.load(path)
    (tmp_path / "text.npz").write_text("not a zip")
    with pytest.raises(ResultsError, match="not a results file"):
        TrajectoryResult.load(tmp_path / "text.npz")


def test_names_with_control_characters_are_escaped_in_tables():
    from mcdm_pin.cli._common import table

    out = table(["cable"], [["c1\nall 101 instants solved\x1b[2J"]])
    assert "\n" not in out.splitlines()[-1] and "\\nall 101 instants solved\\x1b[2J" in out
