"""Stability-aware workspaces: many independent poses -> chunks -> Dask -> a Zarr store.

At every pose (static unless constant rates are given) the case's problem is solved cold, as
``mcdm-pin solve`` solves an instant, and two margins are computed: the smallest common ``f_max``
that would make the pose wrench-feasible and, in case 3, the smallest cone half-angle that would make
it feasible (:mod:`.margins`). Poses: :mod:`.poses`; the work of one chunk: :mod:`.evaluate`; the
store: :mod:`.store`; scheduling: :mod:`.schedule`; the point cloud in the viewer: :mod:`.cloud`.

Use::

    from mcdm_pin import Robot
    from mcdm_pin.workspace import Grid, Setup, compute_workspace, open_workspace, as_grid

    robot = Robot.load("robots/two_link_sr.yaml")
    poses = Grid(robot, {"q1_x": (-1.2, 1.2, 49), "q4_x": (-1.5, 1.5, 61)})
    run = compute_workspace(robot, poses, "arm.zarr", Setup(case=3, cones={"shoulder": 30.0}))
    ds = as_grid(run.open())          # xarray, dims (q1_x, q4_x, ...)
"""

from .errors import WorkspaceError, WorkspaceInterrupted
from .evaluate import PoseSolver, Setup
from .poses import Grid, PoseSet, PosesFile, RandomPoses, coordinate_limits
from .schedule import DEFAULT_CHUNK, RunReport, compute_workspace
from .store import as_grid, is_complete, open_workspace
from .summary import summary

__all__ = ["WorkspaceError", "WorkspaceInterrupted", "Setup", "PoseSolver", "PoseSet", "Grid", "RandomPoses", "PosesFile",
           "coordinate_limits", "compute_workspace", "RunReport", "DEFAULT_CHUNK", "open_workspace",
           "as_grid", "is_complete", "summary"]
