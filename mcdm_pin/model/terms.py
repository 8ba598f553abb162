r"""The terms of the inverse-dynamics problem at one state, in Pinocchio's idiom: the only module that
calls RNEA.

Functions of ``(model, data, cables, q[, v, a])`` with Pinocchio's conventions (``q`` the configuration,
size ``nq``; ``v``, ``a`` size ``nv``; Pinocchio's joint order): :func:`cable_lengths`,
:func:`cable_jacobian` (``L``, ``nv`` columns: the derivative in the tangent space),
:func:`cable_generalized_force` (``-L^T f``), :func:`interaction_map` (``u``, ``R^T`` per physical
joint, child or socket frame) and :func:`cable_terms` (all of them at once, as :class:`Terms`). They
update ``data`` as Pinocchio's own algorithms do (placements, joint Jacobians, RNEA's ``data.f``).
For loops, :class:`TermsEvaluator` keeps its own ``data`` and its index maps.

At a state :math:`(q, \dot q, \ddot q)`:

.. math::

    M(q)\ddot q + h(q,\dot q) = -L(q)^T f, \qquad L = \partial \ell / \partial q,

and for every physical joint :math:`a` the interaction wrench (force and moment the parent exerts on
the child through the joint, at the joint point, in the child link's frame, Pinocchio's ``data.f``
convention) is affine in the cable forces:

.. math::

    p_a = u_a + R_a^T f, \qquad u_a = \text{RNEA}(q,\dot q,\ddot q)\text{'s } f_a, \qquad
    R_a^T = {}^{a}X^{*}_{0} \sum_{b \in \text{subtree}(a)} W_b,

where :math:`W_b` are the cables' signed Plücker vectors on body :math:`b` (:mod:`mcdm_pin.model.geometry`).
Because the joints are passive, the joint-space part :math:`S_a^T p_a` equals
:math:`(M\ddot q + h + L^T f)_a`, zero whenever the equation of motion holds.

**Closed loops** (an OpenSim ``PointConstraint``, :mod:`mcdm_pin.osim.constraints`): with the basis
:math:`B = N K` of the velocities the couplings and loops allow, the equation the unknowns satisfy is
:math:`B^T L^T f - B^T S \tau_{act} = -B^T(M\ddot q + h)`, so ``L`` is ``L_full B``, ``tau`` is
``B^T (M qdd + h)`` and the actuators' rows are ``B^T S`` (``Terms.actuation``, state-dependent). The
loop force :math:`\lambda = \lambda_0 + \Lambda f + \Lambda_{act}\tau_{act}` is recovered from the
equation projected on :math:`N`, and acts on the joints between the loop's bodies:
``u += W lambda_0``, ``RT += W Lambda``, ``RT_act = W Lambda_act`` (``W`` the loop's wrench map).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..exceptions import ModelError, StateError
from .cables import CableSet
from .charts import check_configuration
from .geometry import CableMaps, cable_geometry
from .joints import PhysicalJoint, massless_members, resolve_joints
from .kernel_structs import KeyMaps, Route
from .muscles import tension_state
from .placements import stacked_view
from .routes import RoutePaths, add_levers


@dataclass
class Terms:
    """Everything the problem needs at one state (arrays are owned copies).

    Attributes:
        q: the configuration (nq); qd, qdd: velocity and acceleration (nv each).
        tau: (nv,) ``M qdd + h - tau_passive + L_s^T f_s`` (RNEA, less the known joint forces of springs
            and dampers, plus the passive springs' known tensions, where the model has them); the
            equation of motion is ``L^T f = -tau``.
        M: (nv, nv) joint-space inertia matrix (property, computed on first use).
        h: (nv,) Coriolis, centrifugal and gravity terms (property, computed on first use).
        lengths: (m,) cable lengths, m.
        L: (m, nv) ``d lengths / dq``.
        u: (J, 6) interaction wrenches ``[F; M]`` with zero cable force (child frame; the passive
            springs at their known tensions).
        RT: (J, 6, m) their derivative with respect to the cable forces.
        R_socket: (J, 3, 3) rotation from the child frame to the socket frame of each joint.
        socket_axes: (J, 3) unit socket axes (socket frame).
        points: (P, 3) world position of every route point (then the wraps' tangent points).
        f_min, f_max: (m,) the cables' tension bounds at this instant (a muscle's follow its length and
            speed, :mod:`mcdm_pin.model.muscles`; the others' are fixed).
        muscles: the muscles' :class:`~mcdm_pin.model.muscles.MuscleState` (``None``: no muscles).
        spring_lengths, spring_forces: (s,) the passive springs' lengths (m) and known tensions (N)
            (:mod:`mcdm_pin.model.springs`), already in ``tau`` (``+ L_s^T f_s``) and ``u``
            (``+ R_s^T f_s``); ``None`` without springs.
        basis: with coupled coordinates, ``N`` (nv, n) (:mod:`mcdm_pin.model.couplings`): then ``L``
            is ``d lengths / dz`` (m, n) and ``tau`` is ``N^T (M qdd + h)`` (n,), over the independent
            coordinates ``z``; ``L_full`` is ``d lengths / dq`` (m, nv) either way. With closed loops,
            ``N K`` (nv, n - 3k) in the same roles (module docstring).
        actuation: with closed loops and actuators, the actuators' rows ``basis^T S`` (n, n_act) of the
            equation of motion at this state (``None``: the robot's fixed ``Robot.actuation``).
        RT_act: (J, 6, n_act) the interaction wrenches' derivative with respect to the actuator
            torques (the loop force they induce); ``None`` when zero.
        loop_force: ``(lambda_0, Lambda, Lambda_act)``: the loop forces (N, world) ``lambda_0 +
            Lambda f + Lambda_act tau_act`` (``None`` without loops).
    """

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    lengths: np.ndarray
    L: np.ndarray
    u: np.ndarray
    RT: np.ndarray
    R_socket: np.ndarray
    socket_axes: np.ndarray
    points: np.ndarray
    _evaluator: "TermsEvaluator | None" = field(default=None, repr=False, compare=False)
    finite: bool = True  # tau and L are finite (the dynamics did not overflow)
    _M: np.ndarray | None = field(default=None, repr=False, compare=False)
    f_min: np.ndarray | None = None
    f_max: np.ndarray | None = None
    muscles: object = None
    basis: np.ndarray | None = None
    L_full: np.ndarray | None = None
    spring_lengths: np.ndarray | None = None
    spring_forces: np.ndarray | None = None
    actuation: np.ndarray | None = None
    RT_act: np.ndarray | None = None
    loop_force: tuple | None = None

    # --- M and h on demand: the problem needs only tau = M qdd + h, which RNEA gives directly ----
    @property
    def M(self) -> np.ndarray:
        """(nv, nv) joint-space inertia matrix (computed on first use)."""
        if self._M is None:
            self._M = self._evaluator.mass_matrix(self.q)
        return self._M

    @property
    def v(self) -> np.ndarray:
        """Velocity (Pinocchio's name for ``qd``)."""
        return self.qd

    @property
    def a(self) -> np.ndarray:
        """Acceleration (Pinocchio's name for ``qdd``)."""
        return self.qdd

    @property
    def h(self) -> np.ndarray:
        """(nv,) Coriolis, centrifugal and gravity terms ``tau - M qdd`` (computed on first use)."""
        return self.tau - self.M @ self.qdd

    # --- derived quantities for a force vector f (m,) ---------------------------------------------
    def wrenches(self, f) -> np.ndarray:
        """(J, 6) interaction wrenches ``[F; M]`` of parent on child, child frame, joint point; ``f``
        the cable forces (m,), or the cable forces then the actuator torques (closed loops carry a
        share of the actuators' torques into the wrenches, ``RT_act``)."""
        x = np.asarray(f, dtype=float)
        m = self.RT.shape[2]
        w = self.u + self.RT @ x[:m]
        if self.RT_act is not None and x.shape[0] > m:
            w = w + self.RT_act @ x[m:]
        return w

    def wrenches_socket(self, f) -> np.ndarray:
        """(J, 6) interaction wrenches ``[F; M]`` in each joint's socket frame (same point)."""
        w = self.wrenches(f)
        return np.concatenate([np.einsum("jab,jb->ja", self.R_socket, w[:, :3]),
                               np.einsum("jab,jb->ja", self.R_socket, w[:, 3:])], axis=1)

    def socket_forces(self, f) -> np.ndarray:
        """(J, 3) interaction forces expressed in each joint's socket (parent-side) frame."""
        F = self.wrenches(f)[:, :3]
        return np.einsum("jab,jb->ja", self.R_socket, F)

    def angles_deg(self, f, frame: str = "socket") -> np.ndarray:
        """(J,) interaction angle ``atan2(|F_perp|, F . axis)`` about each socket axis, degrees.

        ``frame='child'`` measures the child-frame force against the same axis taken in the child
        frame (the convention a cone "in the child frame" uses)."""
        F = self.socket_forces(f) if frame == "socket" else self.wrenches(f)[:, :3]
        return interaction_angles(F, self.socket_axes)

    def eom_residual(self, f, extra=None) -> float:
        """Relative equation-of-motion residual ``|tau + L^T f + extra|_inf / scale`` with
        ``scale = max(|tau|_inf, max_i sum_c |L_ci f_c|, |extra|_inf)`` (``extra`` (nv,): further
        generalised forces on the left-hand side, e.g. ``-S tau_act`` of a hybrid robot's actuators)."""
        f = np.asarray(f, dtype=float)
        r = self.tau + self.L.T @ f
        extra_scale = 0.0
        if extra is not None:
            r = r + extra
            extra_scale = float(np.abs(extra).max(initial=0.0))
        scale = max(np.abs(self.tau).max(initial=0.0), (np.abs(self.L.T) @ np.abs(f)).max(initial=0.0),
                    extra_scale, 1e-300)
        return float(np.abs(r).max(initial=0.0) / scale)


def interaction_angles(F: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """Angle between each force ``F[j]`` and axis ``axes[j]``, degrees, in [0, 180]."""
    along = np.einsum("ja,ja->j", F, axes)
    perp = np.linalg.norm(F - along[:, None] * axes, axis=1)
    return np.degrees(np.arctan2(perp, along))


class TermsEvaluator:
    """Computes :class:`Terms` for one model, cable set and set of physical joints, reusing Pinocchio's
    data and the index maps between calls.

    Args:
        model: the ``pin.Model`` (or a :class:`~mcdm_pin.robot.Robot`, whose model, cables and joints
            are used).
        cables: the :class:`~mcdm_pin.model.cables.CableSet` (built for ``model``).
        joints: the physical joints whose interaction wrenches are wanted (``PhysicalJoint`` objects,
            Pinocchio joint names or ids; ``None``: every Pinocchio joint).
        compiled: use the compiled kernel (:func:`mcdm_pin.model.kernels.cable_terms`); ``False``: the
            numpy formulation (the reference the kernel is tested against).

    Only the joints that matter are read back from Pinocchio (those carrying cable points, the
    physical joints' child and parent joints).
    """

    def __init__(self, model, cables: CableSet | None = None, joints=None, compiled: bool = True,
                 couplings=None, passive=None, springs=None, loops=None, actuation=None):
        if cables is None and hasattr(model, "cables") and hasattr(model, "model"):  # a Robot
            couplings = getattr(model, "couplings", None)
            passive = getattr(model, "passive", None)
            springs = getattr(model, "springs", None)
            loops = getattr(getattr(model, "source", None), "loops", None)
            if loops is not None and getattr(model, "actuators", ()):
                from .actuators import actuation_matrix
                actuation = actuation_matrix(model.model.nv, model.actuators)
            model, cables, joints = model.model, model.cables, model.joints
        if not isinstance(cables, CableSet):
            raise ModelError(f"expected a CableSet, got {type(cables).__name__}")
        cables.check_model(model)
        js = resolve_joints(model, joints)
        inside = massless_members(js)
        for k, jid in enumerate(cables.point_joint):
            if int(jid) in inside:
                cable = cables.cables[int(cables.point_cable[k])]
                raise ModelError(f"cable {cable.name!r}: a route point is fixed to the massless body inside "
                                 f"joint {inside[int(jid)]!r}; attach it to the parent or the child link")
        self.compiled = compiled
        self.model = model
        self.cables = cables
        self.couplings = couplings if couplings is not None and len(couplings) else None
        self.passive = passive
        self.loops = loops  # closed loops (PointLoops) or None
        self._S = None if actuation is None or loops is None else np.asarray(actuation, dtype=float)
        self.joints = js
        # passive springs (mcdm_pin.model.springs): their routes' terms, computed as a cable set's
        self.springs = springs if springs is not None and len(springs) else None
        self._springs_ev = None
        if self.springs is not None:
            self.springs.check_model(model)
            self._springs_ev = TermsEvaluator(model, self.springs.geometry, js, compiled=compiled)
        self.data = model.createData()
        nj = model.njoints
        keys = sorted({0} | set(cables.point_joint.tolist()) | {j.child_id for j in js}
                      | {j.parent_id for j in js} | {w.joint for w in cables.wraps}
                      | {w.side_joint for w in cables.wraps if w.side_joint >= 0}
                      | {w.joint for w in getattr(cables, "osim_wraps", ())})
        pos = np.full(nj, -1, dtype=int)
        pos[keys] = np.arange(len(keys))
        self._keys = keys
        self._point_key = pos[cables.point_joint]
        self._child_key = pos[[j.child_id for j in js]].astype(int)
        self._parent_key = pos[[j.parent_id for j in js]].astype(int)
        self._child = [j.child_id for j in js]
        self._R_sp = np.array([j.socket_placement.rotation for j in js]).reshape(len(js), 3, 3)
        sub = _subtree(model)[:, keys]  # sub[i, b] = 1 when key joint b is in the subtree of joint i
        owner = np.zeros(model.nv, dtype=int)  # the joint owning each velocity column
        for j in range(1, nj):
            owner[model.joints[j].idx_v:model.joints[j].idx_v + model.joints[j].nv] = j
        self._sub_v = sub[owner]  # (nv, K)
        self._sub_phys = sub[self._child]  # (J, K)
        self._axes = np.array([j.socket_axis for j in js], dtype=float).reshape(len(js), 3)
        self._keys_i, self._child_i = np.array(keys, dtype=int), np.array(self._child, dtype=int)
        self._views()
        self._h0 = np.zeros((len(keys), 4, 4))
        self._h0[:, 3, 3] = 1.0
        self._zeros = np.zeros(model.nv)
        self._tril = np.tril_indices(model.nv, -1)
        # wrapped routes: their path arrays are rebuilt at every instant and read by the kernel (the
        # numpy reference formulation covers fixed routes only)
        self._routes = RoutePaths(cables, pos) if cables.configuration_dependent else None
        if compiled or self._routes is not None:
            self._setup_kernel(len(keys))
        else:
            self._setup_numpy(len(keys))

    def _setup_kernel(self, K: int) -> None:
        """The cable-terms kernel's fixed arguments (compiled or not: :mod:`mcdm_pin.jit`)."""
        from .. import jit
        from .kernels import csr

        cables = self.cables
        self._kernel = jit.kernels("model.kernels").cable_terms
        self.compiled = True
        self._v_csr = csr([np.flatnonzero(self._sub_v[:, k]).tolist() for k in range(K)], K)
        self._a_csr = csr([np.flatnonzero(self._sub_phys[:, k]).tolist() for k in range(K)], K)
        self._route_args = Route(
            np.ascontiguousarray(cables.point_local, dtype=float),
            self._point_key.astype(np.int64), cables.seg_a.astype(np.int64),
            cables.seg_b.astype(np.int64), cables.seg_cable.astype(np.int64),
            cables.seg_active.astype(np.bool_), np.ascontiguousarray(cables.seg_scale, dtype=float))
        self._kernel_args = tuple(KeyMaps(  # (a plain tuple, as the kernel takes it: solvers._structs)
            *self._v_csr, *self._a_csr,
            self._child_key.astype(np.int64), self._parent_key.astype(np.int64),
            np.ascontiguousarray(self._R_sp, dtype=float), int(cables.m), len(self.joints)))

    def _setup_numpy(self, K: int) -> None:
        """The numpy reference formulation's index maps (fixed routes)."""
        from scipy import sparse

        cables = self.cables
        self._maps = maps = CableMaps(cables, self._point_key, K)
        # end point e moves with column v when its body is in the subtree of v's joint
        self._end_mask = self._sub_v[:, maps.end_body].T  # (E, nv)
        n_end = len(maps.ends)
        m = cables.m
        self._cable_of_end = sparse.csr_matrix(
            (np.ones(n_end), (maps.end_cable, np.arange(n_end))), shape=(m, n_end))
        # (physical joint, cable) <- end points in the joint's subtree
        rows, cols = [], []
        for a_, subrow in enumerate(self._sub_phys):
            inside_ = np.flatnonzero(subrow[maps.end_body] > 0)
            rows.append(a_ * m + maps.end_cable[inside_])
            cols.append(inside_)
        rows = np.concatenate(rows) if rows else np.zeros(0, int)
        cols = np.concatenate(cols) if cols else np.zeros(0, int)
        self._subtree_of_end = sparse.csr_matrix((np.ones(len(rows)), (rows, cols)),
                                                 shape=(len(self.joints) * m, n_end))

    def check_state(self, q, v=None, a=None):
        """``(q, v, a)`` as float arrays of sizes nq, nv, nv (``None``: zeros), or :class:`StateError`
        (also when coupled coordinates do not follow their couplings)."""
        q, v, a = check_configuration(self.model, q), *self.check_motion(v, a)
        if self.couplings is not None:
            self.couplings.check(q, v, a)
        return q, v, a

    def check_motion(self, v=None, a=None):
        """``(v, a)`` as float arrays of size nv (``None``: zeros), or :class:`StateError`."""
        nv = self.model.nv
        return (self._zeros if v is None else check_vector(v, "qd", nv),
                self._zeros if a is None else check_vector(a, "qdd", nv))

    def __call__(self, q, qd=None, qdd=None, checked: bool = False, data=None) -> Terms:
        """Terms at the configuration ``q`` (nq) with velocity ``qd`` and acceleration ``qdd`` (nv;
        ``None``: zeros). ``checked``: the caller has already verified the three (a trajectory checked
        as a whole). ``data``: a ``pin.Data`` to compute in (default: the evaluator's own)."""
        if not checked:
            q, qd, qdd = self.check_state(q, qd, qdd)
        model = self.model
        own = data is None
        data = self.data if own else data
        pin.computeJointJacobians(model, data, q)
        if own:
            oMi = self.placements()
        else:
            oMi = np.array([data.oMi[j].homogeneous for j in self._keys])
        # (6, nv): each column's motion in the world frame at the origin (eigenpy gives (6,) if nv = 1)
        J = data.J.reshape(6, -1)
        cables = self.cables
        if self.compiled:
            # J.T: C-ordered for any nv (one compiled specialisation; a (6, 1) array counts as C)
            if self._routes is None:
                route, arc = self._route_args, None
            else:
                route, arc = self._routes(oMi, q)
            # (plain tuples at the kernel's boundary: solvers._structs)
            X, _, lengths, L, RT, R_socket, bad = self._kernel(oMi, np.ascontiguousarray(J.T), tuple(route),
                                                               self._kernel_args)
            if bad >= 0:
                raise StateError(f"cable {cables.cables[route.seg_cable[bad]].name!r}: a segment has zero "
                                 f"length at this configuration, so its direction is undefined")
            if arc is not None:
                lengths += arc
                if self._routes._osim is not None:  # OpenSim's moving points' own terms, its levers
                    L += self._routes.L_extra
                    add_levers(self._routes, L, RT, J, X, oMi, self._sub_v, self._sub_phys, self._child_key)
        else:
            oR, op = oMi[:, :3, :3], oMi[:, :3, 3]
            geo = cable_geometry(cables, oR, op, self._maps)
            X, lengths = geo.points, geo.lengths
            RT, L = self._numpy_cable_maps(geo.w, J.copy(), oR, op)
            R_socket = (oR[self._parent_key] @ self._R_sp).transpose(0, 2, 1) @ oR[self._child_key]
            bad = -1 if np.isfinite(L).all() else -2
        tau = pin.rnea(model, data, q, qd, qdd).copy()
        if own:
            u = self._f[self._child_i]
        else:
            u = np.array([data.f[c].vector for c in self._child]).reshape(len(self._child), 6)
        if self.passive is not None:  # known joint forces (springs, dampers) help the cables
            tau -= self.passive(q, qd)
        spring_lengths = spring_forces = None
        if self._springs_ev is not None:  # known spring tensions: to the right-hand side, into p
            st = self._springs_ev(q, qd, qdd, checked=True)
            spring_lengths, spring_forces = st.lengths, self.springs.forces(st.lengths)
            tau += st.L.T @ spring_forces
            u = u + st.RT @ spring_forces
        f_min, f_max, state = self._tension_bounds(lengths, L, qd)
        basis, L_full, loop = None, L, {}
        if self.loops is not None:
            basis, L, tau, u, RT, loop = self._loop_terms(q, tau, L, u, RT)
        elif self.couplings is not None:
            basis, L, tau = self.couplings.project(q, L, tau)
        return Terms(q=q.copy(), qd=qd.copy(), qdd=qdd.copy(), tau=tau, lengths=lengths, L=L, u=u,
                     RT=RT, R_socket=R_socket, socket_axes=self._axes, points=X, _evaluator=self,
                     finite=bad != -2 and bool(np.isfinite(tau.sum())), f_min=f_min, f_max=f_max,
                     muscles=state, basis=basis, L_full=L_full, spring_lengths=spring_lengths,
                     spring_forces=spring_forces, **loop)

    def _views(self) -> None:
        """Pinocchio's placements and joint wrenches read through strided views of this evaluator's own
        data (they follow every update): one gather per instant for the rows needed."""
        nj, d = self.model.njoints, self.data
        self._oR = stacked_view(d.oMi, nj, lambda M: M.rotation)
        self._op = stacked_view(d.oMi, nj, lambda M: M.translation)
        self._f = stacked_view(d.f, nj, lambda f: f.vector)

    def placements(self) -> np.ndarray:
        """(K, 4, 4) the homogeneous placements of the key joints in the evaluator's own data (as
        updated by the last kinematics pass)."""
        oMi = self._h0.copy()
        oMi[:, :3, :3] = self._oR[self._keys_i]
        oMi[:, :3, 3] = self._op[self._keys_i]
        return oMi

    def _loop_terms(self, q, tau, L, u, RT):
        """``(basis, L, tau, u, RT, extra)`` with the closed loops (module docstring): the basis ``N K``,
        ``L`` and ``tau`` in it, the wrenches with the loop force's share, and the Terms fields
        ``actuation``, ``RT_act``, ``loop_force`` (one compiled call:
        :meth:`~mcdm_pin.osim.constraints.PointLoops.terms`)."""
        out = self.loops.terms(q, tau, L, self._S, u, RT, self._child_i)
        extra = dict(loop_force=(out.lam0, out.Lam, None))
        if self._S is not None:
            # G^T lambda = tau0 + L^T f - S tau_act: the actuators' share of lambda
            extra = dict(actuation=out.actuation, RT_act=out.RT_act, loop_force=(out.lam0, out.Lam, out.Lam_act))
        return out.basis, out.L, out.tau, out.u, out.RT, extra

    def _tension_bounds(self, lengths, L, qd):
        """The cables' bounds at this instant and the muscles' state (``None`` without muscles)."""
        cables = self.cables
        if cables.muscles is None:
            return cables.f_min, cables.f_max, None
        k = cables.muscle_index
        if cables.all_muscles:  # every cable a muscle, in order: no gather, no scatter
            state = tension_state(cables.muscles, lengths, L @ qd)
            return state.f_min, state.f_max, state
        state = tension_state(cables.muscles, lengths[k], L[k] @ qd)
        f_min, f_max = cables.f_min.copy(), cables.f_max.copy()
        f_min[k], f_max[k] = state.f_min, state.f_max
        return f_min, f_max, state

    def mass_matrix(self, q) -> np.ndarray:
        """(nv, nv) joint-space inertia matrix at the configuration ``q`` (CRBA, both triangles)."""
        data = self.model.createData()
        M = pin.crba(self.model, data, np.asarray(q, dtype=float)).copy()  # upper triangle filled
        M[self._tril] = M.T[self._tril]
        return M

    def _numpy_cable_maps(self, w, J, oR, op):
        """(RT, L) from the end points' Pluecker vectors, in numpy (the reference formulation)."""
        m = self.cables.m
        # d l / d q_v = sum of the end points' Pluecker vectors, on bodies that v moves, . column v
        L = self._cable_of_end @ ((w @ J) * self._end_mask)
        nJ = len(self._child)
        Wsub = (self._subtree_of_end @ w).reshape(nJ, m, 6).transpose(0, 2, 1)  # world
        Rc, tc = oR[self._child_key], op[self._child_key]
        RcT = Rc.transpose(0, 2, 1)
        F_w, M_w = Wsub[:, :3], Wsub[:, 3:]
        RT = np.empty_like(Wsub)
        RT[:, :3] = RcT @ F_w
        # moment about the joint point: M_w - t x F_w, per joint, for every cable column
        tx, ty, tz = tc[:, 0, None], tc[:, 1, None], tc[:, 2, None]
        Fx, Fy, Fz = F_w[:, 0], F_w[:, 1], F_w[:, 2]
        M_t = np.stack([M_w[:, 0] - (ty * Fz - tz * Fy), M_w[:, 1] - (tz * Fx - tx * Fz),
                        M_w[:, 2] - (tx * Fy - ty * Fx)], axis=1)
        RT[:, 3:] = RcT @ M_t
        return RT, L


def _subtree(model) -> np.ndarray:
    """sub[i, j] = 1 when joint j is in the subtree of joint i (i included)."""
    nj = model.njoints
    sub = np.zeros((nj, nj))
    for j in range(nj):
        k = j
        while True:
            sub[k, j] = 1.0
            if k == 0:
                break
            k = model.parents[k]
    return sub


def check_vector(x, name: str, n: int) -> np.ndarray:
    """``x`` as a float array of length ``n``, or :class:`StateError` naming ``name`` and what was
    wrong (not numbers, the wrong shape, entries that are not finite)."""
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise StateError(f"{name}: expected {n} numbers, got {type(x).__name__}") from None
    if arr.shape != (n,):
        raise StateError(f"{name}: expected a vector of length {n}, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        bad = np.flatnonzero(~np.isfinite(arr))
        raise StateError(f"{name}: expected finite numbers, entries {bad.tolist()} are not")
    return arr


# ------------------------------------------------------------------------- Pinocchio's idiom
def _evaluator(model, cables: CableSet, joints=None) -> TermsEvaluator:
    """The evaluator of ``(model, cables, joints)``, made once and kept in the cable set."""
    if not isinstance(cables, CableSet):
        raise ModelError(f"expected a CableSet, got {type(cables).__name__}")
    cables.check_model(model)
    js = resolve_joints(model, () if joints is None else joints)
    key = tuple((j.name, j.pin_ids, j.child_id, j.parent_id, j.socket_axis.tobytes()) for j in js)
    ev = cables._evaluators.get(key)
    if ev is None:
        ev = cables._evaluators[key] = TermsEvaluator(model, cables, js)
    return ev


def cable_terms(model, data, cables: CableSet, q, v=None, a=None, joints=None) -> Terms:
    """Every term at ``(q, v, a)`` (``None``: zeros): lengths, ``L``, ``M a + h`` and, for
    ``joints`` (physical joints, Pinocchio joint names or ids; ``None``: none), the interaction wrench
    maps. Computed in ``data``."""
    return _evaluator(model, cables, joints)(q, v, a, data=data)


def cable_lengths(model, data, cables: CableSet, q) -> np.ndarray:
    """(m,) cable lengths at the configuration ``q``, metres."""
    return cable_terms(model, data, cables, q).lengths


def cable_jacobian(model, data, cables: CableSet, q) -> np.ndarray:
    """(m, nv) ``L = d lengths / dq``: row i maps a velocity ``v`` to cable i's rate of lengthening."""
    return cable_terms(model, data, cables, q).L


def cable_generalized_force(model, data, cables: CableSet, q, f) -> np.ndarray:
    """(nv,) the generalised force ``-L^T f`` of cable tensions ``f`` (N), Pinocchio's ``tau`` convention
    (``M a + h = tau``)."""
    L = cable_jacobian(model, data, cables, q)
    f = check_vector(f, "f", cables.m)
    return -(L.T @ f)


def interaction_map(model, data, cables: CableSet, joints, q, v=None, a=None, frame: str = "child"):
    """``(u, RT)``: the interaction wrenches ``p = u + RT @ f`` of ``joints`` at ``(q, v, a)``,
    ``u`` (J, 6) and ``RT`` (J, 6, m), ``[F; M]`` at each joint point, in each child frame
    (``frame='child'``) or socket frame (``frame='socket'``)."""
    if frame not in ("child", "socket"):
        raise ModelError(f"frame must be 'child' or 'socket', got {frame!r}")
    t = cable_terms(model, data, cables, q, v, a, joints=joints)
    if frame == "child":
        return t.u, t.RT
    Rs = t.R_socket
    u = np.concatenate([np.einsum("jab,jb->ja", Rs, t.u[:, :3]), np.einsum("jab,jb->ja", Rs, t.u[:, 3:])], axis=1)
    RT = np.concatenate([Rs @ t.RT[:, :3], Rs @ t.RT[:, 3:]], axis=1)
    return u, RT


def compute_terms(robot, q, qd=None, qdd=None, compiled: bool = True) -> Terms:
    """Terms of a :class:`~mcdm_pin.robot.Robot` at one state (convenience wrapper; reuse a
    :class:`TermsEvaluator` in loops). ``q``: configuration (nq) or coordinates (nv)."""
    ev = TermsEvaluator(robot, compiled=compiled)
    return ev(robot.check_configuration(q), qd, qdd)
