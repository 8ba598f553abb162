"""Shared fixtures: the bundled 2-link robot and paths."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# the tests run on the compiled kernels (a clean clone compiles them once, before the first solve: the
# first pytest-xdist worker to need them compiles, the others wait on the compile's lock; the uncompiled
# path of a first run has its own tests: tests/test_uncompiled.py)
os.environ.setdefault("MCDM_PIN_JIT", "wait")

REPO = Path(__file__).resolve().parents[1]
TWO_LINK = REPO / "robots" / "two_link_sr.yaml"
TWO_LINK_URDF = REPO / "urdf" / "two_link_sr.urdf"


@pytest.fixture(scope="session")
def two_link():
    from mcdm_pin import Robot

    return Robot.load(TWO_LINK)


@pytest.fixture(scope="session")
def chromium():
    """A Chromium for the render tests; they skip with the install hint when there is none (tests
    never install software: .ci/run installs Debian's chromium before running them)."""
    from mcdm_pin.viewer import find_chromium
    from mcdm_pin.viewer.screenshot import INSTALL_HINT

    exe = find_chromium()
    if exe is None:
        pytest.skip(f"no Chromium for the render tests: {INSTALL_HINT}")
    return exe
