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


def test_the_compiled_solvers_read_their_thresholds_from_the_settings():
    """Every limit and tolerance of the compiled solvers is a field of Settings (kernel_limits copies
    each one, so a changed value reaches the kernels without a recompile), and a changed one changes
    what they do: a shorter step fraction costs the interior-point method iterations for the same
    answer, a minimum step above any step ends it as a breakdown, and a bound is guessed held for the
    next instant only when its multiplier is above active_set_keep of the largest."""
    from mcdm_pin.solvers._structs import Limits
    from mcdm_pin.solvers.active_set import kernel_limits
    from mcdm_pin import jit
    from mcdm_pin.solvers._ipm import NUMERICAL
    from mcdm_pin.solvers.ipm import ipm_arguments, ipm_solve

    fields = {f.name: f.default for f in dataclasses.fields(Settings)}
    changed = {name: (value + 1 if isinstance(value, int) else value / 2) for name, value in fields.items()
               if isinstance(value, (int, float)) and name.startswith(("active_set_", "unique_", "ipm_"))}
    s = DEFAULT.replace(**changed)
    got = kernel_limits(s, 7)
    assert got.max_pivots == 7 and len(got) == len(Limits._fields)
    values = set(changed.values())
    assert all(v in values for name, v in got._asdict().items() if name != "max_pivots"), got
    assert {v for name, v in changed.items() if name not in ("warm_max_pivots", "polish_max_pivots",
                                                                "ipm_crossover_pivots")} == set(got[1:])

    # minimise 1/2 |x|^2 + c^T x over x1 + x2 + x3 = 1, 0 <= x <= 1: x3 at its lower bound
    qp = QPData(np.eye(3), np.array([-1.0, -2.0, 3.0]), 0.0, np.ones((1, 3)), np.ones(1), np.zeros(3), np.ones(3),
                [])
    base = ipm_solve(qp)
    slow = ipm_solve(qp, DEFAULT.replace(ipm_step_fraction=0.3, ipm_crossover_gap=1e-12))
    fast = ipm_solve(qp, DEFAULT.replace(ipm_crossover_gap=1e-12))
    assert base.status == slow.status == fast.status == "optimal"
    assert slow.iterations > fast.iterations
    np.testing.assert_allclose(slow.x, base.x, atol=1e-8)
    # (without the crossover, which would answer from where the iterations stopped)
    kqp, cones, limits = ipm_arguments(qp, DEFAULT.replace(ipm_min_step=0.999, ipm_step_fraction=0.5))
    limits = limits._replace(crossover_gap=0.0)  # (the entry point takes plain tuples: solvers._structs)
    assert jit.kernels("solvers._fast").ipm_answer(*map(tuple, (kqp, cones, limits))).code == NUMERICAL
    assert list(base.active.state) == [0, 0, 1]
    assert list(ipm_solve(qp, DEFAULT.replace(active_set_keep=1.0)).active.state) == [0, 0, 0]
