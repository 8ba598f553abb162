"""RMR's equality constraint evaluated in OpenSim itself (the ``opensim`` package), as RMR's MATLAB code
builds it (``RMR_analysis.m``, ``findInducedAccelerationsForceMomentsGH.m`` at commit ``d40ebd8``):

- muscles: ``Millard2012EquilibriumMuscle`` with ``ignore_tendon_compliance`` and
  ``ignore_activation_dynamics`` set, equilibrated at the frame's state; each muscle's force is
  overridden by ``a F_0 f_L f_V cos(alpha) + F_0 f_P cos(alpha)`` (OpenSim's multipliers at that state;
  no fibre damping);
- the 17 ``CoordinateActuator``s: force ``optimal_force * control`` (``setControls``, unbounded);
- the state: every coordinate set from RMR's filtered IK (``setValue(..., False)``: no assembly onto the
  clavicle-scapula loop) and its speed from the same differentiation;
- the constraint: the forward-dynamics accelerations (``realizeAcceleration``, the ``PointConstraint``
  enforced by Simbody) equal the data's, coordinate by coordinate (in a shrug, ``plane_elv`` and
  ``axial_rot`` dropped). fmincon (``sqp``) holds it to ``TolCon = 1e-2`` *relative* to the violation
  at its start ``x0`` (activations 0.1, controls 0).

Used by ``tools/rmr_study.py --audit``; needs the ``opensim`` package (the test extra).
"""

from __future__ import annotations

import numpy as np

SHRUG_DROPPED = ("plane_elv", "axial_rot")


class OpenSimRMR:
    """RMR's model set-up in OpenSim; ``frame`` sets a state, ``accelerations`` runs forward dynamics."""

    def __init__(self, osim_path, names, shrug: bool = False):
        import opensim as osim

        self.osim = osim
        osim.Logger.setLevelString("error")
        self.model = osim.Model(str(osim_path))
        muscles = self.model.getMuscles()
        self.n_muscles = muscles.getSize()
        self.muscles = [osim.Millard2012EquilibriumMuscle.safeDownCast(muscles.get(i)) for i in range(self.n_muscles)]
        for m in self.muscles:
            m.set_ignore_tendon_compliance(True)
            m.set_ignore_activation_dynamics(True)
        self.state = self.model.initSystem()
        acts = self.model.getActuators()
        self.acts = [osim.ScalarActuator.safeDownCast(acts.get(i)) for i in range(acts.getSize())]
        for m in self.acts[:self.n_muscles]:
            m.overrideActuation(self.state, True)
        self.f_max = np.array([m.getMaxIsometricForce() for m in self.muscles])
        self.coords = [self.model.getCoordinateSet().get(n) for n in names]
        self.names = tuple(names)
        self.kept = np.array([not (shrug and n in SHRUG_DROPPED) for n in names])
        self.matter = self.model.getMatterSubsystem()
        for i, c in enumerate(self.coords):
            c.setSpeedValue(self.state, i + 1.0)
        u = np.array([self.state.getU().get(i) for i in range(self.state.getNU())])
        self.slot = [int(np.flatnonzero(u == i + 1.0)[0]) for i in range(len(names))]
        self.active = self.passive = None

    def frame(self, q, u, t: float = 0.0) -> None:
        """Set coordinates ``q`` and speeds ``u`` (rad, m; the names' order) as RMR does, and read the
        muscles' active and passive force per unit activation (``AMuscForce``, ``PMuscForce``)."""
        s = self.state
        s.setTime(t)
        for c, qi, ui in zip(self.coords, q, u):
            c.setValue(s, float(qi), False)
            c.setSpeedValue(s, float(ui))
        self.model.realizeVelocity(s)
        self.model.equilibrateMuscles(s)
        self.controls = self.model.getControls(s)
        m = self.muscles
        fl = np.array([x.getActiveForceLengthMultiplier(s) for x in m])
        fv = np.array([x.getForceVelocityMultiplier(s) for x in m])
        fp = np.array([x.getPassiveForceMultiplier(s) for x in m])
        cos = np.array([x.getCosPennationAngle(s) for x in m])
        self.active, self.passive = fl * fv * self.f_max * cos, fp * self.f_max * cos

    def muscle_forces(self, x) -> np.ndarray:
        return self.active * np.asarray(x[:self.n_muscles]) + self.passive

    def accelerations(self, x) -> np.ndarray:
        """The coordinates' forward-dynamics accelerations for RMR's unknowns ``x`` (activations, then
        the coordinate actuators' controls in the model's order)."""
        osim, s = self.osim, self.state
        for m, f in zip(self.muscles, self.muscle_forces(x)):
            m.setOverrideActuation(s, float(f))
        for act, c in zip(self.acts[self.n_muscles:], x[self.n_muscles:len(self.acts)]):
            act.setControls(osim.Vector(1, float(c)), self.controls)
        self.model.realizeVelocity(s)
        self.model.setControls(s, self.controls)
        self.model.realizeAcceleration(s)
        return np.array([c.getAccelerationValue(s) for c in self.coords])

    def times_mass(self, r) -> np.ndarray:
        """``M r`` (OpenSim's mass matrix at the state; names' order in and out)."""
        vec = self.osim.Vector(len(r), 0.0)
        for i, ri in zip(self.slot, r):
            vec.set(i, float(ri))
        out = self.osim.Vector()
        self.matter.multiplyByM(self.state, vec, out)
        return np.array([out.get(i) for i in self.slot])


def audit(motion: str, cone: bool, xsol, every: int = 10) -> dict:
    """Where RMR's residual in our equation comes from, at every ``every``-th frame of RMR's states:
    RMR's answer in RMR's own constraint (OpenSim's forward dynamics at RMR's filtered IK: the largest
    acceleration error, rad/s^2 or m/s^2, and its ratio to the error at fmincon's start ``x0``, which
    ``TolCon`` bounds by 1e-2; in a shrug, apart, the accelerations of the two coordinates RMR frees), our muscle forces at RMR's answer against OpenSim's (RMR's force model),
    and our equation's residual against the one OpenSim predicts, ``-(N K)^T E^T M r`` (``r`` the
    acceleration error, ``M`` OpenSim's mass matrix, ``E^T`` its forces in Pinocchio's coordinates)."""
    from mcdm_pin.inverse_dynamics import InverseDynamics
    from mcdm_pin.osim import speeds
    from mcdm_pin.osim.rmr import (IK_FOLDER, N_ACTUATORS, N_MUSCLES, _unknowns, rmr_kinematics, rmr_problem,
                                   rmr_robot, rmr_states)
    from mcdm_pin.problem import Context

    robot = rmr_robot(motion)
    q_t, u_t, a_t = rmr_kinematics(IK_FOLDER / f"{motion.upper()}.mot")
    names = list(q_t.labels)
    unit = np.array([1.0 if n.startswith("ground_thorax_t") else np.pi / 180.0 for n in names])
    ref = OpenSimRMR(robot.source.maps.source, names, motion.startswith("shrug"))
    maps = robot.source.maps
    cv = [int(maps.coordinate_v[maps.coordinates.index(n)]) for n in names]
    ident = InverseDynamics(robot, rmr_problem(robot, cone))
    x0 = np.r_[np.full(N_MUSCLES, 0.1), np.zeros(N_ACTUATORS)]
    rows = np.arange(0, len(xsol), every)

    rec = {k: [] for k in ("acc", "ratio", "freed", "force", "eom", "predicted_diff")}
    for row, q, v, a in zip(rows, *rmr_states(robot, motion, rows)):
        x = xsol[row, :N_MUSCLES + N_ACTUATORS]
        ref.frame(q_t.data[row] * unit, u_t.data[row] * unit, row / 100.0)
        a_data = a_t.data[row] * unit
        r = ref.accelerations(x) - a_data  # all coordinates (in a shrug RMR leaves two free: reported apart)
        r0 = (ref.accelerations(x0) - a_data) * ref.kept
        terms = ident.evaluate(q, v, a)
        qp = ident.problem.assemble(terms, Context(robot))
        y = _unknowns(robot, terms.muscles, x)
        n = terms.tau.shape[0]
        ours = qp.A[:n] @ y - qp.b[:n]
        tau = np.zeros(robot.model.nv)
        tau[cv] = ref.times_mass(r)
        predicted = -terms.basis.T @ speeds.forces_to_pin(maps.angular, q, tau)
        rec["acc"].append(np.abs(r * ref.kept).max())
        rec["ratio"].append(np.abs(r * ref.kept).max() / max(1.0, np.abs(r0 * ref.kept).max()))
        rec["freed"].append(np.abs(r * ~ref.kept).max(initial=0.0))
        rec["force"].append(np.abs(y[robot.cables.muscle_index] - ref.muscle_forces(x)).max())
        rec["eom"].append(np.abs(ours).max())
        rec["predicted_diff"].append(np.abs(ours - predicted).max())
    return dict(motion=motion, cone=cone, frames=len(rows), **{k: np.array(v) for k, v in rec.items()})


def audit_table(audits) -> str:
    """The audit's table (markdown)."""
    lines = ["| motion | cone | frames | RMR's acceleration error p50/max | / error at x0, max | freed coordinates' "
             "error max | muscle force ours - OpenSim, max (N) | our residual p50/max (N m) | ours - OpenSim's "
             "prediction, max (N m) |", "|" + "---|" * 9]
    for d in audits:
        lines.append(f"| {d['motion'].upper()} | {'with GH' if d['cone'] else 'without'} | {d['frames']} | "
                     f"{np.median(d['acc']):.3g} / {d['acc'].max():.3g} | {d['ratio'].max():.2g} | "
                     f"{d['freed'].max():.3g} | "
                     f"{d['force'].max():.2g} | {np.median(d['eom']):.3g} / {d['eom'].max():.3g} | "
                     f"{d['predicted_diff'].max():.2g} |")
    return "\n".join(lines)
