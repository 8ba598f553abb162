"""Batch mode: a trajectory cut into contiguous pieces solved in parallel on Dask, the runtime of the
workspaces (:mod:`mcdm_pin.runtime`), then stacked in order.

Each piece is warm-started along itself, and starts solving :data:`OVERLAP` instants before its first
own one (answers discarded), so that its first own instant is warm-started as in the sequential run,
not solved cold by another path. Every instant's answer is the verified optimum of the same problem,
and the least-norm one where the optimum is not unique, so the results equal the sequential run's to
the solver's tolerance.

What travels to a worker is data: the pickled robot and problem, the solver's name (or the
:class:`~mcdm_pin.solvers.Solver` given, pickled, and copied fresh per task), the runner's options and the piece's states; the
worker builds its own :class:`~mcdm_pin.inverse_dynamics.InverseDynamics` once per task. No module
state is shared and nothing is forked.
"""

from __future__ import annotations

import pickle

import numpy as np

from .exceptions import ProblemError
from .results import concat_columns, instant_columns
from .runtime import check_scheduler, close, connect

OVERLAP = 3  # instants a piece solves before its own first one, to warm its solver up
CONNECT_TIMEOUT_S = 20  # to reach a tcp:// scheduler


def pieces(n: int, workers: int) -> list[tuple[int, int]]:
    """``workers`` contiguous ``(start, stop)`` ranges covering ``range(n)`` (none empty)."""
    bounds = np.linspace(0, n, workers + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


class Recipe:
    """What a worker needs to build the runner: the robot and problem pickled together (the problem's
    constraints refer to the robot), the solver and the runner's options."""

    def __init__(self, ident):
        self.runner = type(ident)  # (pickled by reference: its module and name)
        self.data = pickle.dumps((ident.robot, ident.problem), protocol=pickle.HIGHEST_PROTOCOL)
        self.options = dict(solver=ident.solver_spec, soften=ident.soften, diagnose=ident.diagnose,
                            blas_threads=ident.blas_threads, settings=ident.settings)

    def build(self):
        """A runner of its own (a :class:`~mcdm_pin.solvers.Solver` given is copied fresh: tasks on
        one worker share this recipe, not their warm starts)."""
        robot, problem = pickle.loads(self.data)
        options = dict(self.options)
        if not isinstance(options["solver"], str):
            options["solver"] = options["solver"].fresh()
        return self.runner(robot, problem, **options)


def solve_piece(recipe: Recipe, traj, start: int, stop: int) -> dict:
    """Instants ``start`` to ``stop`` of ``traj`` (checked already), warm-started from ``OVERLAP``
    instants before: their :func:`~mcdm_pin.results.instant_columns` (stacked arrays travel back far
    faster than per-instant objects)."""
    ident = recipe if not isinstance(recipe, Recipe) else recipe.build()
    lead = min(OVERLAP, start)
    return instant_columns(ident._solve_range(traj, range(start - lead, stop))[lead:])


def solve_batch(ident, traj, workers: int, scheduler: str = "local") -> dict:
    """The columns of ``traj`` (checked already) solved by ``ident`` in ``workers`` pieces on
    ``scheduler`` (:mod:`mcdm_pin.runtime`; ``inline``: the pieces one after another in this
    process, each with ``ident`` itself)."""
    check_scheduler(scheduler, None, ProblemError)
    parts = pieces(len(traj), workers)
    if scheduler == "inline":
        return concat_columns([solve_piece(ident, traj, a, b) for a, b in parts])
    client, cluster = connect(scheduler, workers if scheduler == "local" else None, CONNECT_TIMEOUT_S,
                              ProblemError)
    try:
        recipe = client.scatter(Recipe(ident), broadcast=True)
        futures = [client.submit(solve_piece, recipe, traj, a, b, pure=False) for a, b in parts]
        return concat_columns(client.gather(futures))
    finally:
        close(client, cluster)


__all__ = ["OVERLAP", "pieces", "Recipe", "solve_piece", "solve_batch"]
