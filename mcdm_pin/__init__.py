"""mcdm-pin: inverse dynamics of multilink cable-driven manipulators (MCDMs).

The data flow, one module per arrow::

    URDF + sidecar --robot--> Robot --terms--> Terms (M, h, L, u, R^T)
        --problem--> QPData --solvers--> Solution --inverse_dynamics--> results (.npz/.csv)

Quick use::

    from mcdm_pin import Robot, InverseDynamics, load_trajectory
    robot = Robot.load("robots/two_link_sr.yaml")
    run = InverseDynamics.for_case(robot, 3).solve_trajectory(load_trajectory(robot, "traj1"))
"""

from .constraints import CableForceBounds, EquationOfMotion, InteractionCone
from .exceptions import (McdmError, MissingPackageError, ModelError, ProblemError, ResultsError, SidecarError,
                         SolverError, StateError, TrajectoryError)
from .inverse_dynamics import InverseDynamics
from .objectives import MinCableForces, MinCableForceSum, MinInteractions, Smoothing
from .problem import Problem, case_problem
from .results import InstantResult, TrajectoryResult
from .robot import Robot
from .settings import Settings
from .sidecar import load_sidecar
from .solvers import get_solver
from .model.terms import Terms, TermsEvaluator, compute_terms
from .trajectory import Trajectory, csv_trajectory, load_trajectory, quintic_trajectory

__version__ = "0.1.0"

__all__ = [
    "Robot", "load_sidecar", "Terms", "TermsEvaluator", "compute_terms", "Trajectory",
    "load_trajectory", "quintic_trajectory", "csv_trajectory", "Problem", "case_problem",
    "MinCableForces", "MinCableForceSum", "MinInteractions", "Smoothing", "EquationOfMotion",
    "CableForceBounds", "InteractionCone", "get_solver", "InverseDynamics", "Settings", "InstantResult",
    "TrajectoryResult", "McdmError", "SidecarError", "ModelError", "StateError", "TrajectoryError",
    "ProblemError", "SolverError", "ResultsError", "MissingPackageError",
]
