"""An exported robot inside OpenSim, evaluated from our coordinates: the state, the mass matrix, inverse
dynamics, cable lengths and moment arms, each in our coordinate order (for the export's tests and the
benchmark peer).

Every coordinate of the export is one OpenSim coordinate with the same name whose generalized speed is
its rate (pin, slider and custom joints with identity functions), so a state is a permutation of ours:
:attr:`OpenSimModel.slot` maps OpenSim's ``Q`` (and ``U``) entries to our coordinate indices.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import ModelError
from .opensim import default_optimal_force, describe, opensim_model, require_opensim


def to_numpy(x) -> np.ndarray:
    """An OpenSim/SimTK ``Vector`` or ``Matrix`` as a numpy array (a copy)."""
    return np.array(x.to_numpy(), dtype=float)


class OpenSimModel:
    """The OpenSim model of a robot, initialised, with our coordinates <-> OpenSim's state.

    Args:
        robot: a :class:`~mcdm_pin.robot.Robot`.
        optimal_force: :math:`F_0` of every cable (default: the largest ``f_max``).
        path: read the model from this ``.osim`` file (written by
            :func:`~mcdm_pin.export.opensim.export_opensim` for ``robot``) instead of building it.

    Attributes:
        model, state: the ``opensim.Model`` and its working state (``initSystem``'s).
        spec: the :func:`~mcdm_pin.export.opensim.describe` data; ``optimal_force``: :math:`F_0`.
        slot: (nv,) our coordinate index of each entry of OpenSim's ``Q`` (and ``U``).
        actuators: the cables' ``PathActuator`` objects, in our cable order.
    """

    def __init__(self, robot, optimal_force: float | None = None, path=None):
        self.osim = osim = require_opensim()
        self.spec = describe(robot)
        if path is None:
            self.optimal_force = (default_optimal_force(self.spec) if optimal_force is None
                                  else float(optimal_force))
            self.model = opensim_model(self.spec, self.optimal_force)
        else:
            self.model = osim.Model(str(path))
        self.state = self.model.initSystem()
        names = self.spec.coordinate_names
        cs = self.model.getCoordinateSet()
        self.coordinates = [cs.get(n) for n in names]
        nv = len(names)
        if self.state.getNQ() != nv or self.state.getNU() != nv:
            raise ModelError(f"the OpenSim model has {self.state.getNQ()} q and {self.state.getNU()} u; "
                             f"expected {nv} (one per coordinate)")
        for i, c in enumerate(self.coordinates):  # tag each coordinate with its index to read the layout
            c.setValue(self.state, float(i + 1), False)
            c.setSpeedValue(self.state, float(i + 1))
        q_tag, u_tag = to_numpy(self.state.getQ()), to_numpy(self.state.getU())
        self.slot = np.rint(q_tag).astype(int) - 1
        if sorted(self.slot.tolist()) != list(range(nv)) or not np.array_equal(np.rint(u_tag).astype(int) - 1,
                                                                              self.slot):
            raise ModelError(f"OpenSim's state layout is not a permutation of our coordinates "
                             f"(q {q_tag.tolist()}, u {u_tag.tolist()})")
        fs = self.model.getForceSet()
        self.actuators = [osim.PathActuator.safeDownCast(fs.get(c.name)) for c in self.spec.cables]
        if path is not None:
            self.optimal_force = float(self.actuators[0].getOptimalForce())
        self.nv, self.m = nv, len(self.actuators)

    # ------------------------------------------------------------------------------------ state
    def vector(self, x) -> "object":
        """Our coordinate-ordered vector as an OpenSim ``Vector`` in ``Q``/``U`` order."""
        x = np.asarray(x, dtype=float)
        v = self.osim.Vector(self.nv, 0.0)
        for k, i in enumerate(self.slot):
            v.set(k, float(x[i]))
        return v

    def ours(self, x_osim) -> np.ndarray:
        """An OpenSim ``Q``/``U``-ordered vector (numpy or ``Vector``) in our coordinate order."""
        x = to_numpy(x_osim) if not isinstance(x_osim, np.ndarray) else x_osim
        out = np.empty(self.nv)
        out[self.slot] = x
        return out

    def set_state(self, x, xd=None, state=None, time: float | None = None):
        """Set coordinates ``x`` and rates ``xd`` (ours; default zero) into ``state`` (default: the
        working state); returns the state."""
        s = self.state if state is None else state
        if time is not None:
            s.setTime(float(time))
        s.setQ(self.vector(x))
        s.setU(self.vector(np.zeros(self.nv) if xd is None else xd))
        return s

    # ---------------------------------------------------------------------------------- dynamics
    def mass_matrix(self, x) -> np.ndarray:
        """(nv, nv) OpenSim's joint-space inertia matrix at ``x``, our order."""
        s = self.set_state(x)
        self.model.realizePosition(s)
        M = self.osim.Matrix()
        self.model.getMatterSubsystem().calcM(s, M)
        M_os = to_numpy(M)
        out = np.empty_like(M_os)
        out[np.ix_(self.slot, self.slot)] = M_os
        return out

    def inverse_dynamics(self, x, xd, xdd) -> np.ndarray:
        """(nv,) generalized forces OpenSim needs for ``xdd`` at ``(x, xd)`` with slack cables
        (``M xdd + h``, gravity included), our order."""
        s = self.set_state(x, xd)
        self.model.realizeVelocity(s)
        tau = self.osim.InverseDynamicsSolver(self.model).solve(s, self.vector(xdd))
        return self.ours(tau)

    def cable_lengths(self, x) -> np.ndarray:
        """(m,) the cables' path lengths at ``x``, metres."""
        s = self.set_state(x)
        self.model.realizePosition(s)
        return np.array([a.getLength(s) for a in self.actuators])

    def moment_arms(self, x) -> np.ndarray:
        """(m, nv) OpenSim's moment arms ``r = -d length / d coordinate`` at ``x`` (metres, or no unit
        for a slider), our order."""
        s = self.set_state(x)
        self.model.realizePosition(s)
        return np.array([[a.computeMomentArm(s, c) for c in self.coordinates] for a in self.actuators])


def compare_with_pinocchio(robot, om: OpenSimModel, samples: int = 5, seed: int = 0) -> dict[str, float]:
    """The export checked against our model (Pinocchio) at ``samples`` random states (coordinates,
    rates and accelerations uniform in [-1, 1]): the largest relative difference, over the states, of
    the mass matrix, the inverse dynamics ``M a + h``, the cable lengths and the moment arms
    (OpenSim's ``r = -L``), each relative to the largest entry of ours."""
    import pinocchio as pin

    from ..model.terms import cable_jacobian, cable_lengths

    rng = np.random.default_rng(seed)
    model, data = robot.model, robot.model.createData()
    worst = dict(mass_matrix=0.0, inverse_dynamics=0.0, cable_lengths=0.0, moment_arms=0.0)

    def rel(ours, theirs):
        return float(np.abs(ours - theirs).max() / max(np.abs(ours).max(), 1e-300))

    for _ in range(samples):
        x, v, a = (rng.uniform(-1.0, 1.0, robot.nv) for _ in range(3))
        q = robot.configuration(x)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        found = dict(mass_matrix=rel(M, om.mass_matrix(x)),
                     inverse_dynamics=rel(pin.rnea(model, data, q, v, a), om.inverse_dynamics(x, v, a)),
                     cable_lengths=rel(cable_lengths(model, data, robot.cables, q), om.cable_lengths(x)),
                     moment_arms=rel(cable_jacobian(model, data, robot.cables, q), -om.moment_arms(x)))
        worst = {k: max(worst[k], found[k]) for k in worst}
    return worst
