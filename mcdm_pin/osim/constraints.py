r"""Closed loops: OpenSim's ``PointConstraint`` (the thoracoscapular model's acromioclavicular joint).

A point constraint holds point :math:`p_1` of body 1 on point :math:`p_2` of body 2:
:math:`\phi(q) = x_2(q) - x_1(q) = 0` (world axes, m), so the motion obeys

.. math:: G \dot q = 0, \qquad G \ddot q + \gamma = 0, \qquad G = J_2 - J_1 \ (3k \times n_v),
          \quad \gamma = \dot G \dot q

(:math:`J_i` the linear rows of the frame Jacobians at the points, world axes; :math:`\gamma` the
points' relative classical acceleration at zero :math:`\ddot q`). Its force is an unknown
:math:`\lambda` (N, world axes): :math:`+\lambda` on body 2 at :math:`p_2`, :math:`-\lambda` on body 1
at :math:`p_1`, the generalized force :math:`G^T\lambda`, and the equation of motion with cable forces
:math:`f` reads :math:`M\ddot q + h = -L^T f + G^T\lambda`.

**Projection (exact).** With the couplings' basis :math:`N` (:mod:`mcdm_pin.model.couplings`,
identity without couplings), the velocities the loop allows are :math:`\dot q = N K w` with
:math:`K` an orthonormal basis of the null space of :math:`G N` (``n x (n - 3k)``). The loop force
does no work along them, so the equation the cables must satisfy is

.. math:: (N K)^T (M\ddot q + h) = -(N K)^T L^T f,

the couplings' projection (``L N``, ``N^T \tau``) with :math:`N K` in place of :math:`N`
(:meth:`PointLoops.basis`). **Recovery.** Once :math:`f` is known the loop force follows from the
equation projected on :math:`N` alone,

.. math:: \lambda = (N^T G^T)^{+}\, N^T (M\ddot q + h + L^T f),

affine in :math:`f` (:meth:`PointLoops.force`); it is exact (zero residual) whenever the projected
equation holds, because the two projections together span all of :math:`N`'s columns. :math:`\lambda`
enters the interaction wrenches as external forces on bodies 1 and 2 in RNEA
(:meth:`PointLoops.external_forces`), so every joint between the loop's bodies carries it; as maps,
:meth:`PointLoops.force_map` gives ``lambda = lambda_0 + Lambda f`` and :meth:`PointLoops.wrench_map`
the joint wrenches' part ``W lambda``, so a joint's interaction wrench ``u + R^T f`` becomes
``(u + W lambda_0) + (R^T + W Lambda) f``.

A state must lie on the loop (:meth:`residual`, :meth:`velocity_residual`,
:meth:`acceleration_residual`): measured motions of the thoracoscapular model do so only to the
accuracy of the tracking that produced them, which these functions report.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .. import jit
from ..exceptions import ModelError
from ..model.kernel_structs import LoopTables
from ..model.placements import stacked_view

RANK_TOL = 1e-10  # relative singular-value threshold of G N's rank
_VIEWS = ("_oR", "_op", "_fp")  # PointLoops' views of its data: made again, never pickled


class PointLoops:
    """The point constraints of a model (module docstring).

    Args:
        model: the Pinocchio model.
        loops: ``(name, frame id at p1, frame id at p2)`` per constraint.
        couplings: the model's :class:`~mcdm_pin.model.couplings.Couplings`, or ``None``.
    """

    def __init__(self, model: pin.Model, loops, couplings=None):
        self.model, self.loops, self.couplings = model, tuple(loops), couplings
        self.names = tuple(n for n, _, _ in self.loops)
        self.k = 3 * len(self.loops)
        self.data = model.createData()
        # the wrench map's pairs (a loop point, a joint whose subtree holds it: the point's joint and
        # its ancestors): the joint, the point's frame, its sign and its loop, as index arrays
        pairs = []
        for i, (_, a, b) in enumerate(self.loops):
            for fid, sign in ((b, 1.0), (a, -1.0)):
                j = int(model.frames[fid].parentJoint)
                while j > 0:
                    pairs.append((j, fid, sign, i))
                    j = int(model.parents[j])
        self._views()
        self._pair_joint = np.array([p[0] for p in pairs], dtype=np.int64)
        self._pair_frame = np.array([p[1] for p in pairs], dtype=np.int64)
        self._pair_sign = np.array([p[2] for p in pairs], dtype=float)
        self._pair_loop = np.array([p[3] for p in pairs], dtype=np.int64)
        # G's points: frame, sign, loop, and the velocity columns that move each (its joint's support)
        points = [(fid, sign, i) for i, (_, a, b) in enumerate(self.loops) for fid, sign in ((b, 1.0), (a, -1.0))]
        self._pt_frame = np.array([p[0] for p in points], dtype=np.int64)
        self._pt_sign = np.array([p[1] for p in points], dtype=float)
        self._pt_loop = np.array([p[2] for p in points], dtype=np.int64)
        self._pt_cols = np.zeros((len(points), model.nv), dtype=np.bool_)
        for e, (fid, _, _) in enumerate(points):
            for j in model.supports[int(model.frames[fid].parentJoint)]:
                if j > 0:
                    jm = model.joints[j]
                    self._pt_cols[e, jm.idx_v:jm.idx_v + jm.nv] = True
        self._no_actuators = np.zeros((model.nv, 0))
        self._eye = np.eye(model.nv)
        self._eye.flags.writeable = False
        # (a plain tuple, as the kernel takes it: solvers._structs)
        self._tables_plain = tuple(LoopTables(self._pt_frame, self._pt_sign, self._pt_loop, self._pt_cols,
                                              self._pair_joint, self._pair_frame, self._pair_sign, self._pair_loop,
                                              int(model.njoints), self.k))
        self._no_joints = np.zeros(0, dtype=np.int64)  # (instant: no joint's wrenches asked for)

    def _views(self) -> None:
        """The placements read through strided views of ``self.data`` (they follow every update): one
        gather per instant for the pairs' joints and points."""
        m, d = self.model, self.data
        self._oR = stacked_view(d.oMi, m.njoints, lambda M: M.rotation)
        self._op = stacked_view(d.oMi, m.njoints, lambda M: M.translation)
        self._fp = stacked_view(d.oMf, m.nframes, lambda M: M.translation)

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k not in _VIEWS}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._views()  # views of the unpickled data, not copies of the pickled one's memory

    def residual(self, q) -> np.ndarray:
        """(3k,) ``x_2 - x_1`` per loop, world axes (m)."""
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        return np.concatenate([self.data.oMf[b].translation - self.data.oMf[a].translation for _, a, b in self.loops])

    def _jacobians(self, q):
        """``self.data`` with the joints' Jacobians and the joints' and frames' placements at ``q``
        (what :func:`~mcdm_pin.osim.loop_kernels.loop_jacobian` and the wrench map read)."""
        pin.computeJointJacobians(self.model, self.data, np.asarray(q, dtype=float))
        pin.updateFramePlacements(self.model, self.data)
        return self.data

    def jacobian(self, q) -> np.ndarray:
        """(3k, nv) ``G``."""
        d = self._jacobians(q)
        return jit.kernels("osim.loop_kernels").loop_jacobian(d.J, self._fp, self._pt_frame, self._pt_sign,
                                                              self._pt_loop, self._pt_cols, self.k)

    def bias(self, q, v) -> np.ndarray:
        """(3k,) ``gamma``: the relative classical acceleration of the points at zero ``qdd``."""
        m, d = self.model, self.data
        pin.forwardKinematics(m, d, np.asarray(q, dtype=float), np.asarray(v, dtype=float), np.zeros(m.nv))
        pin.updateFramePlacements(m, d)
        acc = lambda f: pin.getFrameClassicalAcceleration(m, d, f, pin.LOCAL_WORLD_ALIGNED).linear
        return np.concatenate([acc(b) - acc(a) for _, a, b in self.loops])

    def velocity_residual(self, q, v) -> np.ndarray:
        return self.jacobian(q) @ np.asarray(v, dtype=float)

    def acceleration_residual(self, q, v, a) -> np.ndarray:
        return self.jacobian(q) @ np.asarray(a, dtype=float) + self.bias(q, v)

    def _coupling_basis(self, q) -> np.ndarray:
        return self._eye if self.couplings is None else self.couplings.basis(q)

    def basis(self, q) -> np.ndarray:
        """(nv, n - 3k) ``N K``: the velocities the couplings and the loops allow (orthonormal ``K``).

        Raises ModelError if ``G N`` loses rank (the loop's constraints are then not independent)."""
        return self._factor(q, self.jacobian(q))[1]

    def _factor(self, q, G):
        """``(N, N K, (N^T G^T)^+)`` from one SVD ``G N = U diag(s) V^T``: ``K`` the last ``n - 3k``
        columns of ``V`` and ``(N^T G^T)^+ = U diag(1/s) V_{:3k}^T`` (full rank, checked)."""
        N = self._coupling_basis(q)
        s, K, pinv = jit.kernels("osim.loop_kernels").loop_factor(G @ N, self.k)
        self._check_rank(s)
        return N, N @ K, pinv

    def _check_rank(self, s) -> None:
        if s.size and s[-1] <= RANK_TOL * max(1.0, s[0]):
            raise ModelError(f"point constraint(s) {list(self.names)}: G N has rank < {self.k} at this "
                             f"configuration (singular values {s.tolist()})")

    def instant(self, q, tau0, L, S=None):
        """Everything the loops add at one instant, from one Jacobian pass and one SVD:
        ``(N K, lambda_0, Lambda, Lambda_act, W)`` (:meth:`basis`, :meth:`force_map` with ``L``, the
        actuators' ``Lambda_act`` of :meth:`force_map` with ``tau0 = 0`` and ``L = -S^T`` (``None``
        without ``S`` (nv, n_act)), :meth:`wrench_map`)."""
        L = np.ascontiguousarray(L, dtype=float)
        out = self.terms(q, tau0, L, S, np.zeros((0, 6)), np.zeros((0, 6, L.shape[0])), self._no_joints)
        return out.basis, out.lam0, out.Lam, None if S is None else out.Lam_act, out.W

    def terms(self, q, tau0, L, S, u, RT, child):
        """:meth:`instant`'s maps and what they add to an instant's terms, in one compiled call
        (:class:`~mcdm_pin.model.kernel_structs.LoopTerms`): the physical joints' wrenches ``u``
        (Jn, 6) and ``RT`` (Jn, 6, m) with the loop force's share (``child`` (Jn,): each one's Pinocchio
        joint), the actuators' ``RT_act``, and the equation of motion in the basis (``L N K``,
        ``(N K)^T tau0``, ``(N K)^T S``). ``S``: (nv, n_act) or ``None``. The arrays reach the kernel
        C-contiguous, as the compile types them: the uncompiled terms' ``RT`` is a strided view, which,
        handed on as it is, would add a ``loop_terms`` specialisation at runtime."""
        d = self._jacobians(q)
        c_ = np.ascontiguousarray  # (no copy where the array is one already)
        out = jit.kernels("osim.loop_kernels").loop_terms(
            d.J, self._fp, self._oR, self._op, self._tables_plain, self._coupling_basis(q),
            c_(tau0, dtype=float), c_(L, dtype=float),
            self._no_actuators if S is None else c_(S, dtype=float), c_(u, dtype=float), c_(RT, dtype=float), child)
        self._check_rank(out.s)
        return out

    def force(self, q, generalized) -> np.ndarray:
        """(3k,) ``lambda`` (N, world) from ``generalized = M qdd + h + L^T f`` (nv): the least-squares
        solution of ``N^T G^T lambda = N^T generalized`` (exact when the projected equation holds)."""
        N = self._coupling_basis(q)
        A = N.T @ self.jacobian(q).T
        return np.linalg.lstsq(A, N.T @ np.asarray(generalized, dtype=float), rcond=None)[0]

    def external_forces(self, q, lam) -> list:
        """Pinocchio's ``fext`` (one ``pin.Force`` per joint, joint frame) of the loop forces ``lam``:
        ``+lambda`` on body 2 at ``p_2``, ``-lambda`` on body 1 at ``p_1``."""
        m, d = self.model, self.data
        pin.framesForwardKinematics(m, d, np.asarray(q, dtype=float))
        fext = [pin.Force.Zero() for _ in range(m.njoints)]
        lam = np.asarray(lam, dtype=float).reshape(-1, 3)
        for (_, a, b), f in zip(self.loops, lam):
            for fid, sign in ((b, 1.0), (a, -1.0)):
                frame = m.frames[fid]
                j = int(frame.parentJoint)
                R = d.oMi[j].rotation
                local = R.T @ (sign * f)
                fext[j] += pin.Force(local, np.cross(frame.placement.translation, local))
        return fext

    def force_map(self, q, tau0, L=None):
        """``(lambda_0, Lambda)`` with ``lambda = lambda_0 + Lambda f`` (:meth:`force`): ``tau0 = M qdd + h``
        (nv), ``L`` (m, nv) the cables' ``d lengths / dq`` (``None``: no cables, ``Lambda`` empty)."""
        L = np.zeros((0, self.model.nv)) if L is None else np.ascontiguousarray(L, dtype=float)
        s, _, lam0, Lam, _ = jit.kernels("osim.loop_kernels").loop_instant(
            self.jacobian(q), self._coupling_basis(q), np.asarray(tau0, dtype=float), L, self._no_actuators, self.k)
        self._check_rank(s)
        return lam0, Lam

    def wrench_map(self, q) -> np.ndarray:
        """(njoints, 6, 3k) ``W``: what the loop forces ``lambda`` add to RNEA's ``data.f[j]`` (the wrench
        ``[F; M]`` the parent exerts on joint ``j``'s subtree, joint frame, moment about its origin):
        ``W[j] lambda`` is ``data.f[j]`` with the loop forces minus ``data.f[j]`` without. A force on the subtree is one the parent
        need not exert, hence ``W[j] = -`` the sum, over the loop points in the subtree, of the point
        force moved to joint ``j``."""
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        return self._wrench_map()

    def _wrench_map(self) -> np.ndarray:
        """:meth:`wrench_map` at the placements in ``self.data`` (joints' and frames'), for every
        (loop point, joint holding it) pair at once."""
        return jit.kernels("osim.loop_kernels").loop_wrench_map(
            self._oR, self._op, self._fp, self._pair_joint, self._pair_frame, self._pair_sign, self._pair_loop,
            self.model.njoints, self.k)

    def project(self, q, free=None, iterations: int = 50, tol: float = 1e-13) -> np.ndarray:
        """``q`` moved onto the loops: Gauss-Newton on ``phi`` along the couplings' directions, smallest
        steps, moving only the independent coordinates ``free`` (``v`` indices; default: all). A file's
        default pose is in general not on the loop (OpenSim assembles it when it initialises the
        model); this is the same job. Raises ModelError if it does not converge."""
        q = np.array(q, dtype=float)
        for _ in range(iterations):
            r = self.residual(q)
            if np.max(np.abs(r)) < tol:
                return q
            N = self._coupling_basis(q)
            if free is not None:
                cols = self._columns(free)
                N = N[:, cols]
            dz = -np.linalg.pinv(self.jacobian(q) @ N) @ r
            q = pin.integrate(self.model, q, N @ dz)
            if self.couplings is not None:
                q = self.couplings.fill(q)[0]
        raise ModelError(f"point constraint(s) {list(self.names)}: no configuration on the loop found near q "
                         f"(residual {np.max(np.abs(self.residual(q)))} m)")

    def _columns(self, free) -> list:
        """Columns of the couplings' basis of the ``v`` indices ``free`` (independent coordinates)."""
        independent = list(range(self.model.nv)) if self.couplings is None else self.couplings.independent.tolist()
        bad = [int(i) for i in free if int(i) not in independent]
        if bad:
            raise ModelError(f"project: v entries {bad} are not independent coordinates")
        return [independent.index(int(i)) for i in free]
