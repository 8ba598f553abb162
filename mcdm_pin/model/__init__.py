"""The layer below :class:`~mcdm_pin.robot.Robot`, in Pinocchio's idiom: cables on any ``pin.Model``.

A Pinocchio user who holds a ``model`` and its ``data`` gets the cable terms without our YAML::

    import pinocchio as pin
    from mcdm_pin.model import Cable, CableSet, cable_jacobian, interaction_map, physical_joints

    cables = CableSet(model, [Cable("c1", [("universe", (0.2, 0, 0)), ("link1", (0.05, 0, 0.1))], 0.0, 500.0)])
    L = cable_jacobian(model, data, cables, q)                  # (m, nv)
    u, RT = interaction_map(model, data, cables, physical_joints(model), q, v, a)   # p = u + RT f

Modules: :mod:`.cables` (routes on frames), :mod:`.joints` (physical joints of any type, groups such as
Euler triples), :mod:`.charts` (coordinates <-> configuration), :mod:`.terms` (the functions and
:class:`~.terms.TermsEvaluator`), :mod:`.actuators` (hybrid robots), :mod:`.springs` (passive springs:
known tensions that follow their lengths), :mod:`.geometry` and
:mod:`.kernels` (the numpy reference and the compiled pass).
"""

from .actuators import Actuator, actuation_matrix
from .cables import Cable, CableSet, RoutePoint, find_frame
from .charts import configuration, configuration_names, coordinate_names, coordinates, tangent
from .joints import JOINT_TYPES, PhysicalJoint, classify, group, physical_joints, single
from .springs import Spring, SpringSet
from .terms import (Terms, TermsEvaluator, cable_generalized_force, cable_jacobian, cable_lengths,
                    cable_terms, interaction_angles, interaction_map)

__all__ = ["Actuator", "actuation_matrix", "Cable", "CableSet", "RoutePoint", "find_frame", "configuration",
           "configuration_names", "coordinate_names", "coordinates", "tangent", "JOINT_TYPES",
           "PhysicalJoint", "classify", "group", "physical_joints", "single", "Terms", "TermsEvaluator",
           "cable_generalized_force", "cable_jacobian", "cable_lengths", "cable_terms", "interaction_angles",
           "interaction_map", "Spring", "SpringSet"]
