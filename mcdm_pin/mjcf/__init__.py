"""A loader: MuJoCo MJCF files (MyoSuite's models among them) -> Robot, through MuJoCo's own compiler.

:func:`load_mjcf` (a file) and :func:`robot_from_mujoco` (a compiled ``mujoco.MjModel``) give the
:class:`~mcdm_pin.robot.Robot`; :mod:`.model` builds the ``pin.Model`` and the coordinate maps,
:mod:`.tendons` the cables, muscles, motors and couplings. ``Robot.load("model.xml")`` and every command
call it. MuJoCo is the ``mjcf`` extra (``pip install 'mcdm-pin[mjcf]'``).
"""

from .load import is_mjcf, load_mjcf, robot_from_mujoco
from .model import MjcfModel, build_model

__all__ = ["is_mjcf", "load_mjcf", "robot_from_mujoco", "MjcfModel", "build_model"]
