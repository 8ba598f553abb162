"""Shared fixtures: the bundled 2-link robot, paths, and the kernels both ways."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# the tests run on the compiled kernels (a clean clone compiles them once, before the first solve: the
# first pytest-xdist worker to need them compiles, the others wait on the compile's lock; the uncompiled
# path of a first run has its own tests: tests/test_uncompiled.py)
os.environ.setdefault("MCDM_PIN_JIT", "wait")


def _hypothesis_draws_ignore_loaded_modules() -> None:
    """Hypothesis (6.131 on) mixes the literals of the local modules loaded so far into its draws
    (``_get_local_constants``, a scan of ``sys.modules``). Which of our modules, benchmarks and tools a
    pytest-xdist worker has loaded depends on the tests it ran before, so a fixed ``@seed`` gave one
    set of examples alone and another inside the suite (docs/speed.md, "The suite from an empty
    cache"). The pool is held empty here: the examples are then the seed's alone. The hook is
    internal; tests/test_properties.py checks the outcome, so a renamed hook fails a test rather
    than passing unseen."""
    try:
        from hypothesis.internal.conjecture import providers
        from hypothesis.internal.constants_ast import Constants
    except ImportError:  # a hypothesis before the literal scan: nothing to hold
        return
    if hasattr(providers, "_get_local_constants"):
        empty = Constants()
        providers._get_local_constants = lambda: empty


_hypothesis_draws_ignore_loaded_modules()

REPO = Path(__file__).resolve().parents[1]
TWO_LINK = REPO / "robots" / "two_link_sr.yaml"
TWO_LINK_URDF = REPO / "urdf" / "two_link_sr.urdf"


@pytest.fixture(scope="session")
def two_link():
    from mcdm_pin import Robot

    return Robot.load(TWO_LINK)


@pytest.fixture(params=[True, False], ids=["compiled", "uncompiled"])
def kernel_modules(request, monkeypatch):
    """``jit.kernels`` over the compiled kernels (waiting for them) and over their uncompiled Python
    code: a test that takes it runs both ways."""
    from mcdm_pin import jit

    if request.param:
        pytest.importorskip("numba")
        jit.prepare(policy="wait")
    else:
        monkeypatch.setattr(jit, "_COMPILED", False)
    return jit.kernels


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
