"""Documented limits on every input, checked before anything large is allocated.

A hostile or broken file must end in one clear error, not in minutes of work or gigabytes of memory.
Each limit is far above what a real robot or run needs; ``docs/limits.md`` lists them with the reason.
"""

from __future__ import annotations

#: bytes of a sidecar YAML file (the 76-cable neck is ~25 kB)
MAX_SIDECAR_BYTES = 16 * 2**20
#: YAML nodes after expanding aliases (a few hundred bytes of nested aliases expand to billions)
MAX_YAML_NODES = 2_000_000
#: nesting levels of a YAML document (a sidecar needs 6)
MAX_YAML_DEPTH = 64
#: alias uses in one YAML document
MAX_YAML_ALIASES = 10_000
#: bytes of a URDF file (example-robot-data's largest is ~0.5 MB)
MAX_URDF_BYTES = 64 * 2**20
#: joints of a model (Pinocchio joints, the universe included)
MAX_JOINTS = 10_000
#: cables of a robot, and points on one cable's route
MAX_CABLES = 100_000
MAX_ROUTE_POINTS = 10_000
#: samples of one trajectory (1e6 instants at 0.3 ms each is five minutes of solving)
MAX_SAMPLES = 1_000_000
#: poses of one workspace (its store holds every pose's forces)
MAX_WORKSPACE_POSES = 100_000_000
#: bytes of a trajectory CSV file
MAX_CSV_BYTES = 512 * 2**20
#: bytes of a CASPR XML file
MAX_XML_BYTES = 64 * 2**20
#: uncompressed bytes of a results .npz file (its arrays are checked before they are read)
MAX_RESULTS_BYTES = 4 * 2**30
#: the largest magnitude of any number read (larger finite values overflow in the dynamics)
MAX_MAGNITUDE = 1e100
#: the smallest cable force bound other than 0, N (squares of smaller forces, ``f^T f``, underflow
#: double precision: the problem's scale is then lost and no check can tell an optimum)
MIN_FORCE_BOUND = 1e-100
