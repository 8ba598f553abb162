"""A robot's validation report (``mcdm-pin info``): checks that need the model, at the zero pose."""

from __future__ import annotations

import numpy as np

from .exceptions import McdmError


def validation_report(robot) -> list[tuple[str, str]]:
    """``[(level, text)]`` with level ``ok``, ``warn`` or ``fail``."""
    from .inverse_dynamics import InverseDynamics
    from .model.terms import compute_terms

    mjcf = getattr(robot.source, "kind", None) == "mjcf"
    loaded = "MJCF compiled by MuJoCo; every moving body's joints" if mjcf else "URDF loaded; every movable URDF joint"
    valid = "sidecar valid; " if robot.sidecar is not None else ""
    out = [("ok", f"{valid}{loaded} ({robot.model.njoints - 1}, {robot.nv} DoF) belongs to one of "
                  f"{len(robot.joints)} physical joints")]
    q0 = robot.reference_coordinates()
    n = robot.nv if robot.couplings is None else robot.couplings.n  # the coordinates the cables must move
    if robot.couplings is not None:
        out.append(("ok", f"{len(robot.couplings)} coupled coordinates follow {n} independent ones"))
    pose = "the reference pose" if mjcf else "q = 0"
    try:
        terms = compute_terms(robot, q0)
    except McdmError as exc:
        return out + [("fail", f"cannot evaluate the model at {pose}: {exc}")]
    eig = np.linalg.eigvalsh(terms.M)
    tol = 1e-12 * max(1.0, float(np.abs(eig).max()))
    empty = _massless_subtrees(robot.model)
    if empty:
        out.append(("fail", f"the body moved by joint {empty[0]!r} and everything after it have no mass and "
                            f"no inertia: the mass matrix is singular there and its motion has no dynamics "
                            f"(give the child link an <inertial>)"))
    elif eig.min() > tol:
        out.append(("ok", f"mass matrix positive definite at {pose} (eigenvalues {eig.min():.3g} .. "
                          f"{eig.max():.3g})"))
    elif eig.min() >= -tol:
        out.append(("warn", f"mass matrix singular at {pose} (smallest eigenvalue {eig.min():.3g}): some body "
                            f"has no inertia about an axis it turns about; inverse dynamics is still defined "
                            f"(forward dynamics, e.g. mcdm-pin verify, is not)"))
    else:
        out.append(("fail", f"mass matrix indefinite at {pose} (smallest eigenvalue {eig.min():.3g}): some "
                            f"body's inertia is not physical"))
    rank = np.linalg.matrix_rank(terms.L, tol=1e-9 * max(1.0, np.abs(terms.L).max()))
    if rank == n:
        sv = np.linalg.svd(terms.L, compute_uv=False)
        out.append(("ok", f"cables span all {n} DoF at {pose} (rank L = {rank}, condition "
                          f"{sv[0] / sv[-1]:.3g})"))
    else:
        out.append(("warn", f"cables span only {rank} of {n} DoF at {pose} (rank L = {rank}): "
                            f"a singular pose, where some accelerations cannot be produced; check the "
                            f"poses your trajectories visit"))
    from .conditioning import wrench_closure

    closure = wrench_closure(robot, q0, terms.L)
    out.append(("ok" if closure.closed else "warn", f"at {pose}: {closure.message}"))
    if robot.m <= n:
        out.append(("warn", f"{robot.m} cables for {n} DoF: a cable robot needs more cables "
                            f"than DoF to keep every cable in tension"))
    res = InverseDynamics.for_case(robot, 1).solve(q0)
    name = "the reference pose" if mjcf else "the zero pose"
    if res.found:
        case1 = "min f^T f" if robot.cables.muscles is None else "min sum a^2"
        out.append(("ok", f"holds {name} against gravity with forces in bounds "
                          f"({case1}: peak {np.max(res.f):.4g} N)"))
    else:
        out.append(("warn", f"cannot hold {name} against gravity within the cable bounds "
                            f"({res.status}: {res.message})"))
    for j in robot.joints:
        if j.cone_deg is not None:
            out.append(("ok", f"joint {j.name}: stability cone {j.cone_deg:g} deg about socket axis "
                              f"{np.round(j.socket_axis, 6).tolist()}"))
    return out


def _massless_subtrees(model) -> list[str]:
    """Joints whose whole subtree (the body they move and everything after it) has no mass and no
    inertia."""
    nj = model.njoints
    mass = np.array([model.inertias[j].mass + np.abs(model.inertias[j].inertia).sum() for j in range(nj)])
    total = mass.copy()
    for j in range(nj - 1, 0, -1):
        total[model.parents[j]] += total[j]
    return [model.names[j] for j in range(1, nj) if total[j] == 0.0]
