"""How the uniqueness of each compiled answer is decided, over every shipped robot's trajectories.

    python tools/uniqueness_survey.py [--cases 2 3] [--trajectories 2] [--robots 'robots/**/*.yaml']

For every answer of the compiled stages (the warm active set, the interior-point method's crossover)
whose objective is not strictly convex (case 1 is always unique), one of:

- ``vertex``: the strongly active rows ``J`` have full column rank (the first factor of
  :func:`mcdm_pin.solvers.least_norm.is_unique`);
- ``factor``: ``H + gamma J^T J - thr I`` has a Cholesky factor (its second);
- ``exact only``: neither factor exists, but the exact test (the null space of ``J`` by an SVD, the
  smallest eigenvalue of the Hessian of the Lagrangian on it, above the same threshold) proves the
  optimum unique: an instant on which the least-norm stage runs although it need not;
- ``face``: not unique by any test (the least-norm stage picks the answer).

The library decides with the two factors alone; ``exact only`` counts what that leaves to the
least-norm stage (which returns the optimum itself where the optimum is unique).

Two more columns count how the least-norm stage answered, per instant it worked on: ``on the face``
(the face's own least-norm point, :mod:`mcdm_pin.solvers._face_qp`) and ``by the chain`` (a cone
not held broke there, or the small method did not converge).
"""

from __future__ import annotations

import argparse
import collections
import sys

import numpy as np


def classify(qp, sol, settings) -> str:
    """``vertex``, ``factor``, ``exact only`` or ``face`` (module docstring) for ``sol`` on ``qp``."""
    from mcdm_pin.solvers import least_norm as LN

    free, rows, curv = LN._strongly_active(qp, sol, settings)
    nf = int(free.sum())
    if nf == 0:
        return "vertex"
    J = LN._active_rows(qp, free, rows)
    if LN._full_column_rank(J):
        return "vertex"
    H = (qp.P + curv)[np.ix_(free, free)]
    hscale = max(np.abs(qp.P).max(initial=0.0), 1e-300)
    thr = settings.unique_rel * hscale
    if LN._definite_beyond(H, J, thr, hscale, settings.unique_penalty):
        return "factor"
    if J.shape[0]:
        _, s, Vt = np.linalg.svd(J, full_matrices=True)
        Z = Vt[int((s > 1e-10 * max(s.max(initial=0.0), 1e-300)).sum()):].T
    else:
        Z = np.eye(nf)
    if Z.shape[1] == 0:
        return "exact only"
    Hr = Z.T @ H @ Z
    return "exact only" if np.linalg.eigvalsh(0.5 * (Hr + Hr.T)).min() > thr else "face"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cases", nargs="+", type=int, default=[2, 3])
    p.add_argument("--trajectories", type=int, default=2, help="the first N trajectories of each sidecar")
    p.add_argument("--robots", default="robots/**/*.yaml", help="glob, relative to the repository")
    args = p.parse_args(argv)

    from stage_survey import robot_runs

    from mcdm_pin import jit
    from mcdm_pin.solvers import active_set, ipm
    from mcdm_pin.solvers import least_norm as LN

    jit.prepare(policy="wait")
    tally: collections.Counter = collections.Counter()
    current: dict = {}
    compiled_answer = active_set.compiled_answer

    def spy(qp, out, **fields):  # every compiled answer passes through here (warm and crossover)
        sol = compiled_answer(qp, out, **fields)
        if sol.status == "optimal" and not qp.strictly_convex():
            tally[(current["label"], classify(qp, sol, current["settings"]))] += 1
        return sol

    active_set.compiled_answer = ipm.compiled_answer = spy
    face = LN._face

    def face_spy(*args):  # every face the least-norm stage works on, and whether it answers there
        out = face(*args)
        tally[(current["label"], "on the face" if out.direct else "by the chain")] += 1
        return out

    LN._face = face_spy
    for label, ident, traj in robot_runs(args.robots, args.cases, args.trajectories):
        current.update(label=label, settings=ident.settings)
        ident.solve_trajectory(traj, progress=False)
    kinds = ("vertex", "factor", "exact only", "face", "on the face", "by the chain")
    print("| robot, trajectory, case | " + " | ".join(kinds) + " |")
    print("|---|" + "---|" * len(kinds))
    for run in sorted({r for r, _ in tally}):
        print(f"| {run} | " + " | ".join(str(tally[(run, k)]) for k in kinds) + " |")
    totals = {k: sum(c for (_, kk), c in tally.items() if kk == k) for k in kinds}
    print("| **all** | " + " | ".join(str(totals[k]) for k in kinds) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
