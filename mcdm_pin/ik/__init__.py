"""Task-space trajectories -> joint trajectories by inverse kinematics (pink on Pinocchio).

:mod:`.space` defines the task coordinates of a frame (position of a point, Euler angles) with their
Jacobian and bias; :mod:`.solve` solves a sampled task trajectory into positions, velocities and
accelerations and checks them by forward kinematics. Needs the optional extra ``ik`` (``pin-pink``).
"""

from .solve import TaskSolution, fk_coordinates, fk_error, solve_task
from .space import CONVENTIONS, LETTERS, TaskKinematics, TaskSpace, euler_angles, euler_rotation

__all__ = ["CONVENTIONS", "LETTERS", "TaskKinematics", "TaskSolution", "TaskSpace", "euler_angles", "euler_rotation",
           "fk_coordinates", "fk_error", "solve_task"]
