"""The uncompiled path: what a first run on a new machine uses while the kernels compile in the
background (numpy cable terms; Clarabel and ProxQP answer, the polish in numpy). Its answers equal the
compiled path's."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, load_trajectory, jit

from .conftest import TWO_LINK


@pytest.mark.parametrize("case", [1, 2, 3])
def test_uncompiled_path_answers_like_the_compiled_one(case, two_link):
    """traj1 subsampled (t = 0.5 s included: the arm at rest, the equation of motion of rank 3 of 4,
    every force at its lower bound, where Clarabel's interior point failed the KKT check before the
    numpy polish), against the compiled path, to 1e-6 of the largest force."""
    traj = load_trajectory(two_link, "traj1").subsample(11)
    assert 0.5 in np.round(traj.t, 9)
    compiled = InverseDynamics.for_case(two_link, case).solve_trajectory(traj, progress=False)
    mp = pytest.MonkeyPatch()
    try:
        mp.setattr(jit, "_READY", False)
        mp.setattr(jit, "prepare", lambda *a, **k: False)
        robot = Robot.load(TWO_LINK)
        ident = InverseDynamics.for_case(robot, case)
        assert not ident.evaluate.compiled
        run = ident.solve_trajectory(traj, progress=False)
    finally:
        mp.undo()
    assert run.found.all(), run.message[~run.found]
    assert not any(s.startswith(("ipm", "warm")) for s in run.stage)
    np.testing.assert_allclose(run.f, compiled.f, rtol=0, atol=1e-6 * np.abs(compiled.f).max())
