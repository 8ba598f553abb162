"""CASPR model files (XML) -> a URDF + a cable sidecar (YAML) + exact trajectories.

CASPR (darwinlau/CASPR, MATLAB) describes a multilink cable-driven manipulator in ``*_bodies.xml``
(links and joints), ``*_cables.xml`` (cable sets: cables and passive springs) and ``*_trajectories.xml``. :func:`import_caspr`
converts them (:mod:`.bodies` says what every joint type becomes, :mod:`.cables` what each cable model
becomes, :mod:`.trajectories` and :mod:`.sampling` how every trajectory type is sampled exactly as CASPR
samples it). ``docs/caspr.md`` lists what the import does with each model of CASPR's library.
"""

from .bodies import JOINT_KINDS, CasprBodies, CasprLink, read_bodies
from .cables import SPRING_TYPES, STIFFNESS_CABLES, CasprCable, CasprCableSet, cable_sets, read_cables
from .convert import CasprImport, import_caspr
from .sampling import SamplingError, Samples, sample, to_ours
from .trajectories import CasprPoint, CasprTrajectory, TrajectoryFile, matlab_colon, read_trajectories

__all__ = ["JOINT_KINDS", "SPRING_TYPES", "STIFFNESS_CABLES", "CasprBodies", "CasprCable", "CasprCableSet", "CasprImport", "CasprLink", "CasprPoint",
           "CasprTrajectory", "SamplingError", "Samples", "TrajectoryFile", "cable_sets", "import_caspr",
           "matlab_colon", "read_bodies", "read_cables", "read_trajectories", "sample", "to_ours"]
