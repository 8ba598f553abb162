"""The compiled hot path (issue 6) against its numpy reference formulation.

``mcdm_pin.model.kernels.cable_terms`` (numba) replaces the numpy formulation of the cable terms, and
``mcdm_pin.solvers._kkt`` the numpy active-set solve; both must give the same numbers. Tolerance
1e-12 relative: the two compute the same sums in a different order, so they differ by rounding only
(a few ulps of the largest entry).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import seed as hseed

from mcdm_pin import TermsEvaluator
from mcdm_pin.exceptions import StateError
from mcdm_pin.model.kernels import spread

from .conftest import REPO
from .robotgen import robots
from .test_properties import SEED, SETTINGS, load, seeds, state

# what the compiled kernel computes (M, h and tau come from Pinocchio's CRBA/RNEA in both paths, so
# comparing them here would compare a computation with itself; the kernel's L and wrench maps are
# checked against independent references in tests/test_model.py: tangent finite differences and
# Pinocchio's RNEA with the cables as external forces)
FIELDS = ("lengths", "L", "u", "RT", "R_socket", "points")


def assert_same_terms(robot, q, qd, qdd):
    q = robot.check_configuration(q)  # the evaluator takes Pinocchio's configuration (nq)
    fast = TermsEvaluator(robot)(q, qd, qdd)
    ref = TermsEvaluator(robot, compiled=False)(q, qd, qdd)
    for name in FIELDS:
        a, b = getattr(fast, name), getattr(ref, name)
        assert a.shape == b.shape, name
        assert np.abs(a - b).max(initial=0.0) <= 1e-12 * max(1.0, np.abs(b).max(initial=0.0)), name


def test_two_link_kernel_equals_numpy(two_link):
    rng = np.random.default_rng(6)
    for _ in range(20):
        assert_same_terms(two_link, rng.uniform(-1, 1, 4), rng.normal(size=4), rng.normal(size=4))


@hseed(SEED)
@settings(max_examples=30, **SETTINGS)
@given(robots(), seeds)
def test_generated_robots_kernel_equals_numpy(g, seed):
    with tempfile.TemporaryDirectory() as d:
        robot = load(g, d)
        q, qd, qdd, _ = state(robot, seed)
        assert_same_terms(robot, q, qd, qdd)


def test_one_evaluator_along_a_trajectory_equals_fresh_ones(two_link):
    """The evaluator reads Pinocchio's data through cached element references: reused along a
    trajectory it must give what a new evaluator gives at every state."""
    rng = np.random.default_rng(7)
    ev = TermsEvaluator(two_link)
    for _ in range(10):
        q, qd, qdd = rng.uniform(-1, 1, 4), rng.normal(size=4), rng.normal(size=4)
        a, b = ev(q, qd, qdd), TermsEvaluator(two_link)(q, qd, qdd)
        for name in FIELDS:
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_zero_length_segment_is_reported_by_both(two_link):
    """A cable point moved onto the next one of its route: both paths raise the same StateError."""
    r = two_link
    k = int(np.flatnonzero(r.seg_active)[0])
    a, b = r.seg_a[k], r.seg_b[k]
    saved = r.point_local.copy()
    try:
        ev_ref = TermsEvaluator(r, compiled=False)
        # put point b where point a is at q = 0 (both expressed in b's body frame)
        import pinocchio as pin
        data = r.model.createData()
        pin.forwardKinematics(r.model, data, r.pin_q(np.zeros(r.nv)))
        xa = data.oMi[int(r.point_joint[a])].act(saved[a])
        r.point_local[b] = data.oMi[int(r.point_joint[b])].actInv(xa)
        ev_fast = TermsEvaluator(r)
        ev_ref = TermsEvaluator(r, compiled=False)
        msgs = []
        for ev in (ev_fast, ev_ref):
            with pytest.raises(StateError, match="zero length") as err:
                ev(np.zeros(r.nv))
            msgs.append(str(err.value))
        assert msgs[0] == msgs[1]
    finally:
        r.point_local[:] = saved


def test_spread_matches_numpy():
    rng = np.random.default_rng(1)
    for _ in range(50):
        A = rng.normal(size=(5, 7)) * 10.0 ** rng.integers(-6, 6, size=(5, 7))
        A[rng.random((5, 7)) < 0.3] = 0.0
        b = rng.normal(size=5) * 10.0 ** rng.integers(-3, 3, size=5)
        B = np.abs(A)
        rows, cols, bb = B.max(1), B.max(0), np.abs(b)
        rows, cols, bb = rows[rows > 0], cols[cols > 0], bb[bb > 0]
        if not len(rows):
            assert spread(A, b) == 1.0
            continue
        want = max(rows.max() / rows.min(), cols.max() / cols.min(), bb.max() / bb.min() if len(bb) else 1)
        assert spread(A, b) == pytest.approx(want, rel=1e-15)


def test_compile_command_sees_every_kernel(capsys):
    """``mcdm-pin compile --where`` names the cache folder and says it holds a complete compile (this
    session's conftest compiled); the registry holds every entry point the library calls."""
    from mcdm_pin import jit
    from mcdm_pin.cli import main

    jit.prepare(policy="wait")
    names = jit.entry_points()
    assert len(names) >= 10 and "mcdm_pin.solvers._fast.ipm_answer" in names
    assert main(["compile", "--where"]) == 0
    out = capsys.readouterr().out
    assert out.strip() == f"{jit.cache_dir()}: compiled", out


def test_jit_uses_numba_public_api_only_and_starts_no_process():
    """No private numba attribute (``_cache``, ``_cache_hits``, ``insert_user_function``, ...), no
    process but the compile's workers, ``fcntl`` imported only where the platform has it."""
    import ast

    from mcdm_pin import jit

    source = Path(jit.__file__).read_text()
    tree = ast.parse(source)
    private = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute) and n.attr.startswith("_")
               and not n.attr.startswith("__")}
    assert not private & {"_cache", "_cache_hits", "_cache_misses", "_can_compile", "_reset_overloads"}, private
    assert "insert_user_function" not in source and "load_overload" not in source
    # processes only in the explicit compile step (its workers): subprocess is imported there alone
    users = {f.name for f in ast.walk(tree) if isinstance(f, ast.FunctionDef)
             and any(isinstance(n, ast.Import) and n.names[0].name == "subprocess" for n in ast.walk(f))}
    assert users == {"_start_children"} and source.count("import subprocess") == 1
    assert source.count("_start_children(") == 2  # its definition, and its call in the compile
    guarded = [n for n in ast.walk(tree) if isinstance(n, ast.Try)
               and any(isinstance(m, ast.Import) and m.names[0].name == "fcntl" for m in n.body)]
    assert guarded


def _stand_in_cache(monkeypatch, tmp_path, calls):
    """Point jit's stamp and lock at ``tmp_path`` and its registry at ``calls`` (the real cache stays)."""
    from mcdm_pin import jit

    monkeypatch.setattr(jit, "cache_dir", lambda: tmp_path)
    monkeypatch.setattr(jit, "_all_calls", lambda: calls)
    monkeypatch.setattr(jit, "_dispatchers", lambda: [])
    monkeypatch.setattr(jit, "_COMPILED", False)
    return jit


def test_stamp_covers_every_kernel_source(tmp_path, monkeypatch):
    """numba invalidates a cached kernel when its own file changes, not when a kernel it calls in
    another module does (``_fast.py`` calls ``_kkt.py``): the stamp is the digest of every kernel module,
    with each file's (mtime, size), numba's own key of its index. The settings reach the kernels as
    arguments, so settings.py is not among them."""
    from mcdm_pin import jit

    names = {p.name for p in jit.kernel_sources()}
    assert {"kernels.py", "_kkt.py", "_kkt_eq.py", "_kkt_verify.py", "_kkt_linalg.py", "_fast.py", "_ipm.py",
            "_ipm_direction.py", "_ipm_newton.py", "_ipm_structure.py", "_ipm_linalg.py", "_unique.py"} <= names
    assert "jit.py" not in names and "settings.py" not in names
    files = []
    for p in jit.kernel_sources():
        files.append(tmp_path / p.name)
        files[-1].write_bytes(p.read_bytes())
    before = jit.sources_digest(files)
    files[1].write_bytes(files[1].read_bytes() + b"#")
    assert jit.sources_digest(files) != before
    text = jit.stamp_text()
    assert all(f"source {n} " in text for n in names) and "numba " in text
    jit = _stand_in_cache(monkeypatch, tmp_path, [])
    assert not jit.stamp_current()  # no stamp
    jit._write_stamp(tmp_path)
    assert jit.stamp_current()
    monkeypatch.setattr(jit, "sources_digest", lambda paths=None: "another source")
    assert not jit.stamp_current()  # a kernel module changed


def test_interrupted_compile_leaves_no_stamp(tmp_path, monkeypatch):
    """The stamp goes before a compile starts and comes back, whole, only after it ends: a compile
    interrupted (or still running) leaves the cache unstamped, and runs stay uncompiled."""
    seen = []

    class Interrupted(Exception):
        pass

    def kernel(*args):
        seen.append(jit.stamp_current())
        raise Interrupted

    jit = _stand_in_cache(monkeypatch, tmp_path, [(kernel, ())])
    (tmp_path / jit.STAMP).write_text("an old compile's stamp\n")
    with pytest.raises(Interrupted):
        jit.compile_now(quiet=True)
    assert seen == [False] and not (tmp_path / jit.STAMP).exists() and not jit.compiled()
    assert not jit.prepare(policy="auto", quiet=True)
    # a complete compile stamps
    monkeypatch.setattr(jit, "_all_calls", lambda: [(lambda: None, ())])
    jit.compile_now(quiet=True)
    assert jit.stamp_current() and jit.compiled() and not list(tmp_path.glob("*.tmp"))


def test_compile_lock_is_per_install(tmp_path, monkeypatch):
    """The lock lives in the install's cache folder: a compile of another install (another folder)
    never waits on it."""
    from mcdm_pin import jit

    if jit.fcntl is None:
        pytest.skip("no fcntl on this platform: no lock")
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    with jit._Lock(tmp_path / "a", quiet=True) as held:
        assert held.path == tmp_path / "a" / jit.LOCK
        with open(tmp_path / "a" / jit.LOCK, "a") as fh:  # the same install: taken
            with pytest.raises(OSError):
                jit.fcntl.flock(fh, jit.fcntl.LOCK_EX | jit.fcntl.LOCK_NB)
        with jit._Lock(tmp_path / "b", quiet=True):  # another install: free
            pass


def test_constructor_starts_no_process_and_compiles_nothing(monkeypatch, two_link):
    """Under the default policy, an unstamped cache leaves the kernels uncompiled (a note says how to
    compile them) and nothing is started or compiled."""
    import subprocess

    from mcdm_pin import InverseDynamics, jit
    from mcdm_pin.settings import DEFAULT

    def no_process(*a, **k):
        raise AssertionError("a library constructor started a process")

    monkeypatch.setattr(subprocess, "Popen", no_process)
    monkeypatch.setattr(jit, "_COMPILED", False)
    monkeypatch.setattr(jit, "stamp_current", lambda: False)
    monkeypatch.setenv("MCDM_PIN_JIT", "auto")
    ident = InverseDynamics.for_case(two_link, 3)
    assert not jit.compiled()
    assert ident.solver.inner.budget_s == pytest.approx(DEFAULT.budget_s * jit.UNCOMPILED_SLOWDOWN)
    assert ident.solve(np.zeros(two_link.nq)).status in ("optimal", "infeasible")


def test_compiled_scaling_check_agrees_with_scaling_factors(tmp_path):
    """``needs_scaling`` (one compiled pass) says "no scaling" only where ``scaling_factors``' numpy path
    returns None: on the neck (cases 1-3) and on the 2-link arm with masses and bounds scaled by 1e6,
    1e-6 and 1e3 (where it must scale)."""
    from mcdm_pin import InverseDynamics, Robot, jit, load_trajectory
    from mcdm_pin import scaling as S
    from mcdm_pin.model.kernels import needs_scaling
    from mcdm_pin.problem import Context

    from .test_reference import _scaled_arm

    jit.prepare(policy="wait")
    arm = Robot.load(REPO / "robots" / "two_link_sr.yaml")
    traj = load_trajectory(arm, "traj1").subsample(6)
    robots = [Robot.load(REPO / "robots" / "caspr" / "8S_neck" / "8S_neck.yaml"), arm]
    for i, k in enumerate((1e6, 1e-6, 1e3)):
        folder = tmp_path / f"k{i}"
        folder.mkdir()
        robots.append(_scaled_arm(folder, k))
    seen = {True: 0, False: 0}
    for robot in robots:
        tr = load_trajectory(robot, "roll").subsample(6) if robot.name == "8S_neck" else traj
        for case in (1, 2, 3):
            kw = {"cones": {j.name: 15.0 for j in robot.joints if j.type == "spherical"}} if case == 3 else {}
            ident = InverseDynamics.for_case(robot, case, **kw)
            for k in range(len(tr)):
                qp = ident.problem.assemble(ident.evaluate(tr.q[k], tr.qd[k], tr.qdd[k]), Context(robot))
                G, g = qp.cone_arrays()[:2]
                fast = needs_scaling(qp.A.copy(), qp.b.copy(), qp.lb.copy(), qp.ub.copy(), qp.P_diag.copy(),
                                     qp.P_factor.copy(), qp.c.copy(), G.copy(), g.copy(), float(S.SPREAD))
                ready = jit._READY
                try:
                    jit._READY = False  # the numpy path
                    slow = S.scaling_factors(qp)
                finally:
                    jit._READY = ready
                assert fast or slow is None, (robot.name, case, k)
                seen[bool(fast)] += 1
    assert seen[True] >= 10 and seen[False] >= 10, seen  # both outcomes occur
