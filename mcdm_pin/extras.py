"""The optional dependencies, by extra, and the one way to import one.

The core (``pip install mcdm-pin``) needs Pinocchio, numpy, scipy, ProxSuite, Clarabel and PyYAML:
it loads robots and solves on ProxQP, Clarabel and the uncompiled kernels. Everything else is an
extra of ``pyproject.toml``, imported where a feature needs it through :func:`optional`, which raises
:class:`~mcdm_pin.exceptions.MissingPackageError` naming the extra to install:

==============  ======================================================================================
extra           what it brings
==============  ======================================================================================
``numba``       the compiled kernels (``mcdm-pin compile``; without it the same kernels run as Python)
``viewer``      the 3-D viewer (meshcat, u-msgpack-python, pillow)
``plots``       the figures (matplotlib)
``workspace``   workspaces and batch trajectories (dask[distributed], zarr, xarray, pandas)
``mjcf``        MJCF robots (mujoco)
``opensim``     the OpenSim export and peer (opensim)
``ik``          task-space trajectories by inverse kinematics (pin-pink, qpsolvers)
==============  ======================================================================================
"""

from __future__ import annotations

import importlib

from .exceptions import MissingPackageError

# the extra that installs each optional top-level module
EXTRAS = {
    "numba": "numba", "meshcat": "viewer", "umsgpack": "viewer", "PIL": "viewer",
    "matplotlib": "plots", "dask": "workspace", "distributed": "workspace", "zarr": "workspace",
    "xarray": "workspace", "pandas": "workspace", "mujoco": "mjcf", "opensim": "opensim",
    "example_robot_data": "examples", "pink": "ik", "qpsolvers": "ik",
}


def install_hint(extra: str) -> str:
    """The command that installs ``extra``."""
    return f"pip install 'mcdm-pin[{extra}]'"


def optional(module: str, feature: str, extra: str | None = None):
    """``import module`` (dotted names allowed), or :class:`MissingPackageError` saying that
    ``feature`` needs it and which extra installs it (``extra``: default from :data:`EXTRAS`)."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        top = module.split(".")[0]
        missing = getattr(exc, "name", None) or top
        extra = extra or EXTRAS.get(top) or EXTRAS.get(missing.split(".")[0], "all")
        raise MissingPackageError(f"{feature} needs the optional package {missing!r}, which is not "
                                  f"installed: {install_hint(extra)}") from None


__all__ = ["EXTRAS", "install_hint", "optional"]
