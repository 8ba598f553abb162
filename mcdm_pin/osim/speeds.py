r"""OpenSim's speeds ``u`` and Pinocchio's velocity ``v``: equal except for angular-velocity joints.

For most OpenSim coordinates the speed is the coordinate's rate, ``u = \dot q``, as Pinocchio's ``v``
entry is. A ``BallJoint``, ``FreeJoint`` (its rotation) and ``ScapulothoracicJoint`` (its ellipsoid:
abduction, elevation, upward rotation) have three coordinates that are body-fixed x-y-z angles
``(a, b, c)`` of ``E`` in ``F'`` (:mod:`mcdm_pin.osim.joints`), but three speeds that are the angular
velocity of ``E`` in ``F'``, expressed in ``F'`` (Simbody's ``Ball`` and ``Ellipsoid`` mobilizers with
Euler angles), while Pinocchio's entries are the angle rates:

.. math:: u = E(a, b)\,\dot\theta, \qquad
          E = \begin{pmatrix} 1 & 0 & \sin b \\ 0 & \cos a & -\sin a \cos b \\
                              0 & \sin a & \cos a \cos b \end{pmatrix}

(the columns are ``x``, ``Rx(a) y``, ``Rx(a) Ry(b) z``), so ``\dot u = E \ddot\theta + \dot E
\dot\theta`` and, as power is ``\tau_u^T u = \tau_v^T v``, generalized forces map as ``\tau_v = E^T
\tau_u``. ``E`` is singular at ``b = \pm\pi/2`` (gimbal lock), where OpenSim's angles are singular too.
The maps below act on whole vectors (nv), in Pinocchio's ``v`` order; OpenSim's order is
:attr:`~mcdm_pin.osim.model.OsimModel.coordinate_v`.
"""

from __future__ import annotations

import numpy as np


def rates_map(a: float, b: float):
    """``(E, dE/da, dE/db)`` of the module docstring."""
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    E = np.array([[1.0, 0.0, sb], [0.0, ca, -sa * cb], [0.0, sa, ca * cb]])
    Ea = np.array([[0.0, 0.0, 0.0], [0.0, -sa, -ca * cb], [0.0, ca, -sa * cb]])
    Eb = np.array([[0.0, 0.0, cb], [0.0, 0.0, sa * sb], [0.0, 0.0, -ca * sb]])
    return E, Ea, Eb


def to_speeds(angular, q, v) -> np.ndarray:
    """OpenSim's speeds (``v`` order) of Pinocchio's ``v`` at ``q``; ``angular``: the ``v`` (and
    ``q``) indices of each angle triple."""
    u = np.array(v, dtype=float)
    for idx in angular:
        idx = list(idx)
        u[idx] = rates_map(q[idx[0]], q[idx[1]])[0] @ v[idx]
    return u


def from_speeds(angular, q, u, udot=None):
    """Pinocchio's ``v`` (and ``a`` when ``udot`` is given: ``(v, a)``) of OpenSim's speeds ``u`` and
    their rates ``udot`` (``v`` order) at ``q``."""
    v = np.array(u, dtype=float)
    a = None if udot is None else np.array(udot, dtype=float)
    for idx in angular:
        idx = list(idx)
        E, Ea, Eb = rates_map(q[idx[0]], q[idx[1]])
        v[idx] = np.linalg.solve(E, u[idx])
        if a is not None:
            Edot = Ea * v[idx[0]] + Eb * v[idx[1]]
            a[idx] = np.linalg.solve(E, udot[idx] - Edot @ v[idx])
    return v if a is None else (v, a)


def forces_to_pin(angular, q, tau_u) -> np.ndarray:
    """Pinocchio's generalized forces of OpenSim's (``tau_v = E^T tau_u``)."""
    tau = np.array(tau_u, dtype=float)
    for idx in angular:
        idx = list(idx)
        tau[idx] = rates_map(q[idx[0]], q[idx[1]])[0].T @ tau_u[idx]
    return tau


def forces_to_osim(angular, q, tau_v) -> np.ndarray:
    """OpenSim's generalized forces of Pinocchio's (``tau_u = E^{-T} tau_v``)."""
    tau = np.array(tau_v, dtype=float)
    for idx in angular:
        idx = list(idx)
        tau[idx] = np.linalg.solve(rates_map(q[idx[0]], q[idx[1]])[0].T, tau_v[idx])
    return tau
