"""The named structures the model layer's compiled kernels take and return.

numba compiles a ``collections.namedtuple`` into a struct whose fields a kernel reads by name; on
the uncompiled path the same classes are plain Python tuples (as in
:mod:`mcdm_pin.solvers._structs`, the solvers' own). Every field's type is fixed by what the
library passes: one compiled specialisation serves every call.

:data:`KERNEL_STRUCTURES` marks this module as a kernel source for :mod:`mcdm_pin.jit`: numba's
cache keys a kernel by its own file only, so an edit here must invalidate the compiled kernels too.
"""

from __future__ import annotations

from collections import namedtuple

Route = namedtuple("Route", ["point_local", "point_key", "seg_a", "seg_b", "seg_cable", "seg_active", "seg_scale"])
Route.__doc__ = """The cables' routes at an instant: the route points ``point_local`` (P, 3) in the
frame of their key body ``point_key`` (P,); the segments from point ``seg_a`` to point ``seg_b``
of cable ``seg_cable``, whether each spans two bodies (``seg_active``) and its share of its cable's
length and force (``seg_scale``: 1 for a plain route, ``1/divisor`` on a pulley's branch, 0 for a
slot of a configuration-dependent route that is not part of the path at this instant)."""

KeyMaps = namedtuple("KeyMaps", ["v_ptr", "v_idx", "a_ptr", "a_idx", "child_key", "parent_key", "R_sp",
                                 "n_cables", "n_joints"])
KeyMaps.__doc__ = """What the key bodies move and carry, fixed per robot: the velocity columns
that move key body k (CSR ``v_ptr``, ``v_idx``), the physical joints whose subtree holds it (CSR
``a_ptr``, ``a_idx``), each physical joint's child and parent key bodies (``child_key``,
``parent_key``, (Jn,)), each socket frame's rotation in its parent's frame (``R_sp``,
(Jn, 3, 3)), and the numbers of cables and physical joints."""

CableTerms = namedtuple("CableTerms", ["X", "seg_len", "lengths", "L", "RT", "R_socket", "bad"])
CableTerms.__doc__ = """What :func:`mcdm_pin.model.kernels.cable_terms` returns: the route points in
the world (P, 3), the segments' lengths, the cables' lengths (m,), ``L`` (m, nv), ``RT`` (Jn, 6, m)
in each child frame at the joint point, the rotations child frame -> socket frame (Jn, 3, 3), and
the index of a zero-length spanning segment ``bad`` (-1 when none; -2 when ``L`` is not finite)."""

OsimPaths = namedtuple("OsimPaths", ["route_int", "pt_kind", "pt_q", "pt_v", "pt_fun", "pt_float", "fun_ptr",
                                     "knots", "wrap_int", "wrap_float", "wrap_len", "pt_dP"])
OsimPaths.__doc__ = """The tables of the routes that follow OpenSim's rules
(:class:`mcdm_pin.model.route_osim.OsimTables` builds them once per cable set; their columns are
:mod:`mcdm_pin.model.route_osim`'s): one row per route (``route_int``); per route point its kind,
coordinate, velocity column, spline functions and floats (``pt_*``); the splines' knots
(``fun_ptr``, ``knots``); one row per wrap (``wrap_int``, ``wrap_float``); and the work arrays
``wrap_len`` (each wrap's arc) and ``pt_dP`` (each moving point's velocity per coordinate)."""

LoopTables = namedtuple("LoopTables", ["pt_frame", "pt_sign", "pt_loop", "pt_cols", "pair_joint", "pair_frame",
                                       "pair_sign", "pair_loop", "njoints", "k"])
LoopTables.__doc__ = """A model's closed loops, fixed per model (:class:`mcdm_pin.osim.constraints.PointLoops`):
the loop points of ``G`` (frame, sign: + at ``p_2``, - at ``p_1``, loop, and the velocity columns
that move each, ``pt_cols`` (points, nv)), the wrench map's (point, joint whose subtree holds it)
pairs (joint, frame, sign, loop), the model's number of joints and ``k`` (3 per loop)."""

LoopTerms = namedtuple("LoopTerms", ["s", "basis", "lam0", "Lam", "Lam_act", "W", "u", "RT", "RT_act", "actuation",
                                     "L", "tau"])
LoopTerms.__doc__ = """What :func:`mcdm_pin.osim.loop_kernels.loop_terms` returns: ``G N``'s singular values
``s``, the basis ``N K`` (nv, n), the loop force's maps ``lambda = lam0 + Lam f + Lam_act tau_act``,
the joint wrenches' map ``W`` (njoints, 6, k), the physical joints' wrenches with the loop force's
share (``u`` (Jn, 6), ``RT`` (Jn, 6, m), ``RT_act`` (Jn, 6, n_act)), and the equation of motion in
the basis: ``actuation = (N K)^T S``, ``L N K`` (m, n), ``(N K)^T tau0`` (n,)."""

KERNEL_STRUCTURES = (Route, KeyMaps, CableTerms, OsimPaths, LoopTables, LoopTerms)
"""The structures above (the marker :func:`mcdm_pin.jit.kernel_sources` looks for)."""

ScaledQP = namedtuple("ScaledQP", ["c", "A", "b", "lb", "ub", "P", "P_diag", "P_factor", "G", "g", "norm_weight"])
ScaledQP.__doc__ = """What :func:`mcdm_pin.model.scale_kernels.scale_qp` returns: a problem's arrays
scaled by :class:`mcdm_pin.scaling.Scaling`'s factors (``P``, ``P_diag``, ``P_factor`` empty where
the problem has none)."""

ScaledInstant = namedtuple("ScaledInstant", ["scaled", "d", "r", "obj", "cone", "qp"])
ScaledInstant.__doc__ = """What :func:`mcdm_pin.model.scale_kernels.scale_instant` returns: whether the
problem is scaled, :class:`mcdm_pin.scaling.Scaling`'s factors and the scaled arrays
(:class:`ScaledQP`; all empty where ``scaled`` is false)."""

Unscaled = namedtuple("Unscaled", ["x", "objective", "y", "z", "z_cone"])
Unscaled.__doc__ = """What :func:`mcdm_pin.model.scale_kernels.unscale_answer` returns: an answer of the
scaled problem mapped back (point, its objective on the original problem, equations', bounds' and
cones' multipliers; a multiplier array empty where the answer has none)."""

CouplingTable = namedtuple("CouplingTable", ["dep_q", "src_q", "dep_v", "src_v", "col", "coef"])
CouplingTable.__doc__ = """A model's couplings in their order (a source before what depends on it),
fixed per model (:func:`mcdm_pin.model.couplings._table`): each dependent's ``q`` entry and ``v``
index, its source's (-1 for a fixed coordinate), the column of ``N`` its row lands in (the
independent coordinate at its chain's root; -1 where the chain starts at a fixed coordinate) and its
polynomial ``a_0 .. a_4`` (k, 5; zeros for a coupling given by a function)."""
