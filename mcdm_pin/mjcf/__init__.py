"""A loader: MuJoCo MJCF files (MyoSuite's models among them) -> Robot, through MuJoCo's own compiler.

:func:`compile_mjcf` (MuJoCo compiles a file) and :func:`mjcf_parts` (a compiled ``mujoco.MjModel`` ->
the robot's parts) are what ``Robot.load("model.xml")``, ``Robot.from_mujoco(mj)`` and every command
use; :mod:`.model` builds the ``pin.Model`` and the coordinate maps, :mod:`.tendons` the cables,
muscles, motors and couplings. MuJoCo is the ``mjcf`` extra (``pip install 'mcdm-pin[mjcf]'``).
"""

from .load import RobotParts, compile_mjcf, is_mjcf, mjcf_parts
from .model import MjcfModel, build_model

__all__ = ["RobotParts", "compile_mjcf", "is_mjcf", "mjcf_parts", "MjcfModel", "build_model"]
