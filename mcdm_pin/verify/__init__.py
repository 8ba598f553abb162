r"""Forward-dynamics replay: do the computed cable forces really produce the planned motion?

Starting from the first solved state of a :class:`~mcdm_pin.results.TrajectoryResult`, integrate

.. math:: \dot v = \text{ABA}\big(q, v,\; \tau = -L(q)^T f(t)\big)

(Pinocchio's articulated-body algorithm, the cables' generalised force evaluated at the *integrated*
configuration, not the planned one; actuators' torques ``tau_act`` join :math:`\tau` on hybrid robots
and reserves; on robots with coupled coordinates the full equation of motion is solved with the
couplings' constraint forces as unknowns) and compare :math:`q` with the plan at the sample instants
(:mod:`mcdm_pin.verify.replay`). Robots with quaternion joints (native ball or free joints) are
integrated on their configuration manifold (Runge-Kutta-Munthe-Kaas through ``pin.integrate``), and
the error is ``pin.difference`` between the replayed and the planned configuration (rad or m).

**Forcing.** ``hold='linear'`` interpolates :math:`f` linearly between the solved instants,
``hold='zoh'`` holds each instant's forces until the next one, and a callable ``forces(t) -> f``
supplies forces at any time (:func:`resolved_forces` re-solves the inverse-dynamics problem on the
planned state at the integrator's own stage times: "dense output").

**What converges, and at which order.** The integrator takes ``substeps`` equal steps per sample
interval, so every step boundary falls on a sample instant and the interpolated forcing is a
polynomial (linear, or constant) *inside* every step: the ODE being integrated is smooth on each step
and the integrator keeps its full order (RK4: 4; explicit and semi-implicit Euler: 1). Two errors
must be told apart:

* ``self`` error: :math:`\max|q_h - q_{h/2}|` at the samples (Richardson): the integrator's own
  error; it shrinks by :math:`2^p` per halving of the step.
* ``plan`` error: :math:`\max|q_h - q_{plan}|`. With interpolated forces it tends, as the step
  shrinks, to a floor that does not depend on the integrator: the difference between the plan's
  generalised force and that of piecewise-linear forces, :math:`O(\Delta^2)` in the sample spacing
  :math:`\Delta` (``zoh``: :math:`O(\Delta)`). With re-solved forces the exact solution *is* the plan
  (the forces satisfy :math:`M\ddot q + h = -L^T f` on the plan at every time), so the plan error
  itself shrinks at the integrator's order, as long as :math:`f(t)` is smooth: where the optimal
  active set changes :math:`f` has a kink, which costs RK4 its order locally (measured in
  ``docs/trust.md``).

**The verdict** (:func:`judge`, :mod:`mcdm_pin.verify.verdict`): *converged*, *diverged* or *not
converged*, from the observed order and the size of the errors. Under force control a cable robot
can be open-loop unstable (errors grow like :math:`e^{\lambda t}`, :func:`open_loop_growth`): a
replay over the whole run then *diverges* from the plan whatever the step, although the forces are
right. The verdict says so and finds a ``window`` (restart from the plan every few instants) with
which the replay follows the plan.
"""

from .replay import (HOLDS, INTEGRATORS, ORDER, ConvergenceTable, ReplayReport, convergence,
                     open_loop_growth, replay, solved_stretch)
from .resolve import planned_state, problem_from_run, resolved_forces
from .verdict import DIVERGED_FRACTION, Verdict, judge, motion_range

__all__ = ["HOLDS", "INTEGRATORS", "ORDER", "ConvergenceTable", "ReplayReport", "convergence",
           "open_loop_growth", "replay", "solved_stretch", "planned_state", "problem_from_run",
           "resolved_forces", "Verdict", "judge", "motion_range", "DIVERGED_FRACTION"]
