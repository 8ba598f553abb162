r"""MuJoCo as the plant: the robot exported to MJCF (:mod:`mcdm_pin.export.mjcf`), driven by the cable
tensions through its tendon motors, and read back in Pinocchio's coordinates, optionally with sensor
noise.

**Time.** One control tick of ``dt`` seconds holds the commanded tensions (zero-order hold) over
``substeps`` MuJoCo steps of ``dt / substeps`` each (integrator ``RK4`` by default).

**Saturation.** Each motor's ``ctrlrange`` is the cable's ``[f_min, f_max]``: MuJoCo clamps a command
outside it, as a winch saturates. The controller's forces are within the bounds already (to the
answer check's 1e-9 N); :attr:`MujocoPlant.clamped` counts the ticks at which a command was outside by
more than that.

**Sensor noise** (:meth:`MujocoPlant.measure`): ``q_meas = q (+) n_q`` (``pin.integrate``: a rotation
vector in the child frame for ball and free joints) and ``v_meas = v + n_v``, with ``n_q``, ``n_v``
independent, zero-mean Gaussian per coordinate of standard deviations ``noise_q`` (rad or m) and
``noise_v`` (rad/s or m/s).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..exceptions import ProblemError
from ..export.mjcf import _mujoco, export_mjcf


class MujocoPlant:
    """The robot simulated by MuJoCo (module docstring).

    Args:
        robot: the true robot (:class:`~mcdm_pin.robot.Robot`).
        dt: the control period, s; ``substeps``: MuJoCo steps per period; ``integrator``: MuJoCo's.
        noise_q, noise_v: standard deviations of the sensor noise (0: exact measurements).
        seed: of the noise generator.
    """

    def __init__(self, robot, dt: float = 1e-3, substeps: int = 1, integrator: str = "RK4",
                 noise_q: float = 0.0, noise_v: float = 0.0, seed: int = 0):
        mujoco = _mujoco()
        if not (np.isfinite(dt) and dt > 0) or int(substeps) != substeps or substeps < 1:
            raise ProblemError(f"MujocoPlant: expected dt > 0 s and a whole number of substeps >= 1, got "
                               f"dt={dt!r}, substeps={substeps!r}")
        if not (noise_q >= 0 and noise_v >= 0):
            raise ProblemError(f"MujocoPlant: noise_q and noise_v are standard deviations >= 0, got "
                               f"{noise_q!r}, {noise_v!r}")
        self.robot, self.dt, self.substeps = robot, float(dt), int(substeps)
        self.export = export_mjcf(robot, timestep=dt / substeps, integrator=integrator)
        self.mj = self.export.compile()
        self.data = mujoco.MjData(self.mj)
        self._step = mujoco.mj_step
        self._forward = mujoco.mj_forward
        self.noise_q, self.noise_v = float(noise_q), float(noise_v)
        self.rng = np.random.default_rng(seed)
        self.lo, self.hi = robot.f_min, robot.f_max
        self.clamped = 0

    def reset(self, q, v) -> None:
        """Put the plant at ``(q, v)`` (Pinocchio's coordinates), at time 0."""
        self.data.time = 0.0
        self.data.qpos[:] = self.export.qpos(q)
        self.data.qvel[:] = self.export.qvel(q, v)
        self.data.ctrl[:] = 0.0
        self._forward(self.mj, self.data)
        self.clamped = 0

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """The exact ``(q, v)`` (Pinocchio's coordinates)."""
        qpos = self.data.qpos.copy()
        return self.export.q(qpos), self.export.v(qpos, self.data.qvel)

    def measure(self) -> tuple[np.ndarray, np.ndarray]:
        """The measured ``(q, v)``: the state with sensor noise (module docstring)."""
        q, v = self.state()
        if self.noise_q:
            q = pin.integrate(self.robot.model, q, self.rng.normal(0.0, self.noise_q, self.robot.nv))
        if self.noise_v:
            v = v + self.rng.normal(0.0, self.noise_v, self.robot.nv)
        return q, v

    def step(self, f) -> None:
        """Apply tensions ``f`` (N, cable order) for one control period."""
        f = np.asarray(f, dtype=float)
        if np.any(f < self.lo - 1e-9) or np.any(f > self.hi + 1e-9):
            self.clamped += 1
        self.data.ctrl[:] = f
        for _ in range(self.substeps):
            self._step(self.mj, self.data)
