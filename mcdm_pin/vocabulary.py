"""The package's vocabularies, each defined here once: plain tuples and tables, no imports, so that the
sidecar's parser, the model, the constraints, the solvers and the command line read the same names.
"""

from __future__ import annotations

# joint types a sidecar declares over URDF joints, with how many URDF joints each may take
URDF_JOINT_COUNTS = {"spherical": (1, 3), "revolute": (1,), "prismatic": (1,), "universal": (2,),
                     "planar": (1, 3), "translation": (2, 3), "free": (1,)}
SIDECAR_JOINT_TYPES = tuple(URDF_JOINT_COUNTS)
# every physical joint's type: the sidecar's, and those only other sources give (Pinocchio's native
# helical and ellipsoid joints; an MJCF body's several joints about one point, "composite")
JOINT_TYPES = SIDECAR_JOINT_TYPES + ("helical", "ellipsoid", "composite")
# a spherical joint's coordinates, by its number of URDF joints: one (Pinocchio's quaternion, or
# three ZYX angles) or three revolute joints (Euler XYZ)
SPHERICAL_PARAMETRIZATIONS = {1: ("quaternion", "zyx"), 3: ("euler-xyz",)}
PARAMETRIZATIONS = tuple(sorted({p for ps in SPHERICAL_PARAMETRIZATIONS.values() for p in ps}))
# joints a stability cone may bound: ball joints, and composite joints (an MJCF body's several joints,
# e.g. a shoulder's rotations about one point, where the cone bounds the reaction force's direction)
CONE_TYPES = ("spherical", "composite")
# the frame a cone's axis and force are expressed in: the socket's (parent side) or the child link's
CONE_FRAMES = ("socket", "child")
# how a quintic plan interpolates a ball joint: about one axis, or coordinate by coordinate
SPHERICAL_MODES = ("axis-angle", "per-coordinate")
# the source paper's cases: 1 min f^T f, 2 min interactions, 3 case 2 + stability cones
CASES = (1, 2, 3)
# a wrapping surface's kind (MuJoCo's wrapping geoms)
WRAP_KINDS = ("sphere", "cylinder")
# the solver chains by name (mcdm_pin.solvers.chains)
BACKENDS = ("default", "compiled", "proxqp", "clarabel")
# the first stage of every chain, where the objective is a constant (mcdm_pin.solvers.least_norm)
FLAT_OBJECTIVE_STAGE = "flat_objective"

__all__ = ["URDF_JOINT_COUNTS", "SIDECAR_JOINT_TYPES", "JOINT_TYPES", "SPHERICAL_PARAMETRIZATIONS",
           "PARAMETRIZATIONS", "CONE_TYPES", "CONE_FRAMES", "SPHERICAL_MODES", "CASES", "WRAP_KINDS", "BACKENDS",
           "FLAT_OBJECTIVE_STAGE"]
