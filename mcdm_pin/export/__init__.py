"""Our robots written in other tools' formats: :mod:`.opensim` (an OpenSim ``.osim`` model)."""

from .opensim import MissingPackageError, describe, export_opensim, opensim_model
from .opensim_eval import OpenSimModel

__all__ = ["MissingPackageError", "OpenSimModel", "describe", "export_opensim", "opensim_model"]
