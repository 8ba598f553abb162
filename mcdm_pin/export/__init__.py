"""Our robots written in other tools' formats: :mod:`.opensim` (an OpenSim ``.osim`` model) and
:mod:`.mjcf` (a MuJoCo model, the plant of :mod:`mcdm_pin.control`)."""

from .mjcf import MjcfExport, export_mjcf
from .opensim import MissingPackageError, describe, export_opensim, opensim_model
from .opensim_eval import OpenSimModel

__all__ = ["MissingPackageError", "MjcfExport", "OpenSimModel", "describe", "export_mjcf", "export_opensim",
           "opensim_model"]
