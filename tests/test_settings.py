"""One settings object (mcdm_pin.settings.Settings): its values checked, and passed down to every stage,
the answer check and the runner."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Settings, SolverError, load_trajectory
from mcdm_pin.qp import QPData
from mcdm_pin.settings import DEFAULT
from mcdm_pin.solvers import Solution, make_solver
from mcdm_pin.solvers.check import kkt_problems


def test_settings_reject_unknown_fields_and_bad_values():
    with pytest.raises(SolverError, match="unknown setting 'eom_tol'.*eom_rel"):
        DEFAULT.replace(eom_tol=1e-9)
    with pytest.raises(TypeError):
        Settings(eom_tol=1e-9)
    for field, bad, expected in [("eom_rel", -1e-8, "positive finite"), ("cone_deg", float("nan"), "positive finite"),
                                 ("ipm_max_iter", 2.5, "integer >= 1"), ("warm_max_pivots", True, "integer >= 1"),
                                 ("same_cut_cos", 1.5, r"\(0, 1\]"), ("budget_s", -1.0, ">= 0 or None")]:
        with pytest.raises(SolverError, match=f"setting '{field}' must be .*{expected}"):
            DEFAULT.replace(**{field: bad})
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT.eom_rel = 1.0
    s = DEFAULT.replace(eom_rel=1e-10, budget_s=None, ipm_correctors=0)
    assert (s.eom_rel, s.budget_s, s.ipm_correctors) == (1e-10, None, 0) and DEFAULT.eom_rel == 1e-8


def test_every_stage_of_a_chain_holds_its_settings():
    s = DEFAULT.replace(unique_penalty=1e4, budget_s=0.5)
    chain = make_solver("default", s)
    assert chain.settings is s and chain.budget_s == 0.5
    for stage in chain.stages:
        assert stage.settings is s, stage.name
    inner = chain.stage("least_norm").inner
    assert inner.budget_s is None and inner.settings == s.replace(budget_s=None)
    assert all(stage.settings is s for stage in inner.stages)  # (the outer deadline bounds them)
    assert chain.fresh().settings is s


def _crafted():
    """``x`` meets ``x1 + x2 = 1`` to ~1e-10 relative, inside its bounds, with consistent duals."""
    qp = QPData(np.eye(2), np.zeros(2), 0.0, np.ones((1, 2)), np.ones(1), np.zeros(2), np.ones(2), [])
    x = np.array([0.5, 0.5 + 1e-10])
    return qp, Solution(x, "optimal", qp.objective(x), y=-x.mean() * np.ones(1), z=np.zeros(2), z_cone=None,
                        verified=False)


def test_a_tighter_eom_tolerance_changes_the_checks_verdict():
    qp, sol = _crafted()
    assert not kkt_problems(qp, sol)
    tight = DEFAULT.replace(eom_rel=1e-12)
    assert any("equation-of-motion" in p for p in kkt_problems(qp, sol, tight))
    out = make_solver("clarabel", tight).stage("check")(qp, sol, float("inf"))
    assert out.status == "inaccurate" and "equation-of-motion residual" in out.message
    assert make_solver("clarabel").stage("check")(qp, sol, float("inf")).status == "optimal"


def test_the_runner_checks_and_budgets_with_its_settings(two_link):
    """An equation-of-motion tolerance below the answer's rounding-size residual (~1e-16) makes the
    runner's check call it inaccurate; a zero budget stops the chain before its first stage."""
    traj = load_trajectory(two_link, "traj2")
    state = traj.q[12], traj.qd[12], traj.qdd[12]
    ok = InverseDynamics.for_case(two_link, 1).solve(*state)
    assert ok.status == "optimal" and ok.eom_residual > 1e-20
    res = InverseDynamics.for_case(two_link, 1, settings=Settings(eom_rel=1e-20)).solve(*state)
    assert res.status == "inaccurate" and "equation-of-motion residual" in res.message
    stalled = InverseDynamics.for_case(two_link, 1, settings=Settings(budget_s=0.0), diagnose=False)
    assert stalled.solver.inner.budget_s == 0.0 and stalled.solve(*state).status == "budget"
