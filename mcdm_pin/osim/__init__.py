r"""A loader: OpenSim ``.osim`` files -> Robot, read as XML (no OpenSim needed).

:func:`osim_parts` (the robot's parts, as ``Robot.load("model.osim")`` takes them) and
:func:`osim_skeleton` (the skeleton alone); :mod:`.document` reads the file, :mod:`.joints` and
:mod:`.model` build the ``pin.Model``, :mod:`.functions` evaluates OpenSim's functions,
:mod:`.speeds` maps OpenSim's speeds, :mod:`.constraints` handles ``PointConstraint`` loops,
:mod:`.paths` and :mod:`.muscles` read the muscles and their paths, :mod:`.actuators` the
``CoordinateActuator``\ s, :mod:`.motion` motion tables, :mod:`.glenoid` RMR's glenohumeral cone.
"""

from .constraints import PointLoops
from .load import OsimSource, is_osim, osim_parts, osim_skeleton
from .model import OsimModel, build

__all__ = ["PointLoops", "OsimSource", "is_osim", "osim_parts", "osim_skeleton", "OsimModel", "build"]
