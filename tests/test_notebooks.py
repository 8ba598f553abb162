"""The notebooks in notebooks/ run top to bottom, headless and offline (nbclient + ipykernel), so they
stay in sync with the code. Each runs in a temporary folder (its outputs go to ./out there)."""

from __future__ import annotations

import os
import re

import pytest

from .conftest import REPO

nbformat = pytest.importorskip("nbformat", reason="pip install -e '.[test]' (nbformat)")
nbclient = pytest.importorskip("nbclient", reason="pip install -e '.[test]' (nbclient)")
pytest.importorskip("ipykernel", reason="pip install -e '.[test]' (ipykernel)")



def _run(name, tmp_path):
    nb = nbformat.read(REPO / "notebooks" / f"{name}.ipynb", as_version=4)
    env_backend = os.environ.get("MPLBACKEND")
    os.environ["MPLBACKEND"] = "Agg"  # inherited by the kernel: never a display
    try:
        nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                resources={"metadata": {"path": str(tmp_path)}}).execute()
    finally:
        if env_backend is None:
            os.environ.pop("MPLBACKEND", None)
        else:
            os.environ["MPLBACKEND"] = env_backend
    return nb


def _text(nb) -> str:
    out = []
    for cell in nb.cells:
        for o in cell.get("outputs", []):
            out.append(o.get("text", ""))
            out.append(str(o.get("data", {}).get("text/plain", "")))
    return "\n".join(out)


def test_quickstart(tmp_path):
    nb = _run("quickstart", tmp_path)
    text = _text(nb)
    assert "case 3: solved 101/101 instants" in text
    assert (tmp_path / "out" / "quickstart_summary.png").stat().st_size > 20_000
    assert (tmp_path / "out" / "quickstart_case3.html").stat().st_size > 100_000


def test_two_link_paper(tmp_path):
    nb = _run("two_link_paper", tmp_path)
    text = _text(nb)
    assert "traj2" in text and "instants > rho*" in text
    for name in ("traj1", "traj2"):
        assert (tmp_path / "out" / f"two_link_{name}_summary.png").is_file()


def test_neck_paper(tmp_path):
    nb = _run("neck_paper", tmp_path)
    text = _text(nb)
    assert "8S_neck" in text and "case 3: solved" in text
    assert (tmp_path / "out" / "neck_case3.html").is_file()


def test_pinocchio_plugin(tmp_path):
    """The model built in code gives the sidecar robot's forces (cases 1-3, to 1e-9 N: the same convex
    problems, so only rounding differs); the cable-driven UR5 solves every instant of its move."""
    import re

    nb = _run("pinocchio_plugin", tmp_path)
    text = _text(nb)
    diffs = [float(x) for x in re.findall(r"case \d: optimal, max \|f_code - f_sidecar\| = ([0-9.e+-]+) N", text)]
    assert len(diffs) == 3 and max(diffs) < 1e-9, text
    assert "solved 41/41 instants" in text


def test_control_loop(tmp_path):
    """One simulated second of CoGiRo's 1 kHz loop against MuJoCo: the platform tracks to the
    millimetre and the figure is written."""
    import re

    pytest.importorskip("mujoco", reason="pip install -e '.[mjcf]'")
    nb = _run("control_loop", tmp_path)
    text = _text(nb)
    assert "ticks 1000" in text, text
    rms = float(re.search(r"position RMS ([0-9.]+) mm", text).group(1))
    assert rms < 1.0, text
    assert (tmp_path / "out" / "control_loop.png").stat().st_size > 20_000


def test_rmr_shoulder(tmp_path):
    nb = _run("rmr_shoulder", tmp_path)
    text = _text(nb)
    assert "without GH: 21/21 optimal" in text and "with GH   : 21/21 optimal" in text, text
    assert "largest GH angle ours 19.03 deg" in text


def test_myosuite_arm(tmp_path):
    pytest.importorskip("mujoco", reason="pip install -e '.[test]' (mujoco: the MJCF loader's compiler)")
    nb = _run("myosuite_arm", tmp_path)
    text = _text(nb)
    assert "27 of them independent; 63 muscles over 97 wrapping surfaces" in text
    for what in ("muscle-tendon lengths", "moment arms"):  # the paths against MuJoCo's
        err = float(re.search(rf"{what}: largest difference to MuJoCo (\S+) m", text).group(1))
        assert err < 1e-9, (what, err)
    assert "without the glenohumeral cone: 26/26 instants optimal" in text
    assert "with the glenohumeral cone: 26/26 instants optimal" in text
    rel = [float(x) for x in re.findall(r"objective equal to Clarabel's within (\S+)", text)]
    assert len(rel) == 2 and max(rel) < 1e-6, rel
    assert "19.03 deg with it" in text  # the cone holds the force on its surface
    before, after = (float(x) for x in re.search(r"rotator cuff\s+mean summed activation (\S+) -> (\S+)", text).groups())
    assert after > 2 * before  # recruitment shifts to the rotator cuff
    assert (tmp_path / "out" / "myosuite_glenohumeral.png").stat().st_size > 20_000
