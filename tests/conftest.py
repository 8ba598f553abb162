"""Shared fixtures: the bundled 2-link robot and paths."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
TWO_LINK = REPO / "robots" / "two_link_sr.yaml"
TWO_LINK_URDF = REPO / "urdf" / "two_link_sr.urdf"
SHARED = REPO.parent / "shared"


@pytest.fixture(scope="session")
def two_link():
    from mcdm_pin import Robot

    return Robot.load(TWO_LINK)


def ensure_chromium() -> str | None:
    """The test set-up for the render test: Debian's ``chromium``, installed with apt-get when it is
    missing and we may (root, apt-get present; package download only, no browser download of its
    own). Returns the executable, or None when it cannot be had here."""
    import os
    import shutil
    import subprocess

    from mcdm_pin.viewer import find_chromium

    exe = find_chromium()
    if exe or os.environ.get("MCDM_PIN_NO_APT"):
        return exe
    if shutil.which("apt-get") is None or os.geteuid() != 0:
        return None
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    for cmd in (["apt-get", "update", "-qq"], ["apt-get", "install", "-y", "-qq", "chromium"]):
        if subprocess.run(cmd, env=env, capture_output=True, timeout=900).returncode != 0:
            return None
    return find_chromium()


@pytest.fixture(scope="session")
def chromium():
    exe = ensure_chromium()
    if exe is None:
        pytest.skip("no Chromium and it cannot be installed here (needs root and apt-get: "
                    "apt-get install chromium)")
    return exe
