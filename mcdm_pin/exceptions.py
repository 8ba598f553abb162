"""The package's own exception types.

Every error raised on bad input derives from :class:`McdmError`. Messages name the file (when there
is one), the key path inside it (``cables[3].route[1].link``) and what was expected, listing the valid
choices where there are few enough to read.
"""

from __future__ import annotations


class McdmError(Exception):
    """Base class of every error mcdm-pin raises on purpose."""


class SidecarError(McdmError, ValueError):
    """A cable sidecar (YAML) is malformed or inconsistent with its URDF.

    Attributes:
        path: the file the problem is in (or ``None`` for data given in code).
        key: the key path inside the file, e.g. ``cables[3].route[1].link``.
        expected: what would have been accepted.
    """

    def __init__(self, path, key: str, expected: str):
        self.path = None if path is None else str(path)
        self.key = key
        self.expected = expected
        where = f"{self.path}: " if self.path else ""
        at = f"{key}: " if key else ""
        super().__init__(f"{where}{at}{expected}")


class ModelError(McdmError):
    """The URDF cannot be loaded or cannot be used as a cable-driven manipulator."""


class StateError(McdmError, ValueError):
    """A state (q, qd, qdd) or a force vector passed to the API has the wrong size or is not finite."""


class TrajectoryError(McdmError, ValueError):
    """A trajectory cannot be built (bad CSV, wrong number of columns, non-increasing time...)."""


class ProblemError(McdmError, ValueError):
    """An objective or constraint is inconsistent with the robot (unknown joint, bad weight...)."""


class SolverError(McdmError):
    """A solver back-end is missing or failed in a way that is not a property of the problem."""


class ResultsError(McdmError, ValueError):
    """A results file cannot be read or does not match the robot."""


class MissingPackageError(McdmError, ImportError):
    """An optional package a feature needs is not installed; the message gives the install command."""


class CasprError(McdmError, ValueError):
    """A CASPR model file (``*_bodies.xml``, ``*_cables.xml``, ``*_trajectories.xml``) cannot be
    converted: malformed, inconsistent, or using a CASPR feature mcdm-pin does not support.

    Attributes:
        path: the XML file.
        element: where in it, e.g. ``link_rigid[num=3, name='C5 bone']/joint@type``.
        expected: what would have been accepted.
    """

    def __init__(self, path, element: str, expected: str):
        self.path = None if path is None else str(path)
        self.element = element
        self.expected = expected
        where = f"{self.path}: " if self.path else ""
        at = f"{element}: " if element else ""
        super().__init__(f"{where}{at}{expected}")


class McdmWarning(UserWarning):
    """Base class of every warning mcdm-pin gives on purpose."""


class InertiaWarning(McdmWarning):
    """A model is used with inertias that no body can have (principal moments breaking the triangle
    inequality), because its source ships them (a CASPR import): its answers are those of the source's
    numbers, not of a physical body (docs/limits.md)."""
