"""The workspace's Zarr store (format 2: stable fixed-width strings, consolidated metadata), which
``xarray.open_zarr(STORE)`` opens.

=========================  ==============================  ============================================
variable                   dimensions                      meaning
=========================  ==============================  ============================================
``q``                      pose, coordinate                the pose, coordinates (rad or m)
``status``                 pose                            as ``mcdm-pin solve``: optimal, infeasible...
``objective``              pose                            the case's objective (NaN without an answer)
``f``                      pose, cable                     cable forces, N
``interaction_wrench``     pose, joint, component          [F; M] of parent on child, child frame, N, N m
``interaction_angle_deg``  pose, joint                     angle of F from the socket axis, degrees
``needed_f_max``           pose                            smallest common f_max that makes the pose
                                                           wrench-feasible, N (``inf``: none)
``needed_cone_deg``        pose                            smallest cone half-angle that makes the pose
                                                           feasible, degrees (case 3; ``inf``: none)
``chunk_done``             chunk                           1 once every variable of the chunk is written
=========================  ==============================  ============================================

Coordinates: ``coordinate``, ``cable``, ``joint``, ``component`` (names), and for a grid one 1-D
coordinate per axis, named after the robot coordinate it varies, with its values (poses run in C
order over the axes: :func:`as_grid` reshapes them). The group's attribute ``workspace`` holds the
run's settings (robot, problem, poses, chunk size, margins); it is written once, at creation.

**Crash safety.** The store is created in a temporary folder and renamed into place; each chunk's
variables are written (each file atomically, by Zarr) before its ``chunk_done`` flag, so a run killed
at any moment leaves flags only on complete chunks; :func:`open_for_resume` drops Zarr's unfinished
temporary files and returns the chunks still to do. Two runs creating one store: the second rename
finds the folder taken and that run stops with a :class:`WorkspaceError`.

**Trust, verified.** Every chunk is written whole, even where all its values equal the fill value
(NaN), so a flagged chunk has one file per variable (the group attribute ``chunk_files`` says so).
Before a flag is trusted (:func:`damaged_chunks`: on resume, and whenever :func:`open_workspace`
opens a store) each variable of each flagged chunk must exist and decode; resume recomputes a
damaged chunk, reading names the store, the chunk and the variable.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import warnings
from pathlib import Path

import numpy as np

from ..extras import optional
from .errors import WorkspaceError
from .evaluate import COMPONENTS, STATUS_DTYPE
from .poses import coordinate_units

FORMAT = 1  # version of this layout, in the attributes
READ_BYTES = 1 << 26  # what damaged_chunks reads at once (64 MB)

UNITS = dict(q="rad or m (per coordinate)", objective="as the case's objective", f="N",
             interaction_wrench="N (F), N m (M)", interaction_angle_deg="deg", needed_f_max="N",
             needed_cone_deg="deg")
DESCRIPTIONS = dict(
    q="pose, in coordinates", status="solver status (the words of mcdm-pin solve)",
    objective="objective value at the answer", f="cable forces",
    interaction_wrench="interaction wrench [F; M] of the parent on the child, child frame, joint point",
    interaction_angle_deg="angle of the interaction force from the socket axis",
    needed_f_max="smallest common f_max with which the equation of motion can be met (cones not "
                 "considered; inf: none)",
    needed_cone_deg="smallest cone half-angle (all cones moved by one angle) with which the pose is "
                    "feasible (inf: none below 90 deg; NaN: no cones)",
    chunk_done="1 when the chunk of poses is written")


def _variables(n: int, nv: int, m: int, J: int) -> dict:
    """name -> (shape, dims, dtype, fill)."""
    nan = float("nan")
    return dict(
        q=((n, nv), ("pose", "coordinate"), "f8", nan),
        status=((n,), ("pose",), STATUS_DTYPE, None),
        objective=((n,), ("pose",), "f8", nan),
        f=((n, m), ("pose", "cable"), "f8", nan),
        interaction_wrench=((n, J, 6), ("pose", "joint", "component"), "f8", nan),
        interaction_angle_deg=((n, J), ("pose", "joint"), "f8", nan),
        needed_f_max=((n,), ("pose",), "f8", nan),
        needed_cone_deg=((n,), ("pose",), "f8", nan))


RESULT_VARIABLES = tuple(_variables(1, 1, 1, 1))


def axis_name(coordinate: str) -> str:
    """The store's name of a grid axis: the coordinate's own name, unless a variable has it."""
    taken = set(RESULT_VARIABLES) | {"chunk_done", "coordinate", "cable", "joint", "component", "pose"}
    return f"grid_{coordinate}" if coordinate in taken else coordinate


def _array(group, name, data_or_shape, dims, dtype, chunks, fill, attrs=None):
    attrs = dict(attrs or {}, _ARRAY_DIMENSIONS=list(dims))
    shape = np.shape(data_or_shape) if not isinstance(data_or_shape, tuple) else data_or_shape
    a = group.create_array(name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill,
                           attributes=attrs)
    if not isinstance(data_or_shape, tuple):
        a[...] = data_or_shape
    return a


def create_store(path, robot, poses, chunk: int, settings: dict) -> None:
    """Create the empty store at ``path`` (an error if something is there)."""
    zarr = optional("zarr", "workspaces")

    path = Path(path)
    if path.exists():
        raise WorkspaceError(f"{path}: already exists; give --resume to complete it, or another --out")
    try:  # a folder of this run's own, beside the store (rename does not cross file systems)
        tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.creating-", dir=path.parent))
    except OSError as exc:
        raise WorkspaceError(f"{path}: cannot create the store ({exc.strerror or exc})") from None
    n, nchunks = len(poses), -(-len(poses) // chunk)
    try:
        g = zarr.open_group(str(tmp), mode="a", zarr_format=2)
        for name, (shape, dims, dtype, fill) in _variables(n, robot.nv, robot.m, len(robot.joints)).items():
            chunks = (chunk,) + shape[1:]
            _array(g, name, shape, dims, dtype, chunks, fill,
                   dict(units=UNITS.get(name, ""), description=DESCRIPTIONS[name]))
        _array(g, "chunk_done", (nchunks,), ("chunk",), "u1", (1,), None,
               dict(description=DESCRIPTIONS["chunk_done"], chunk_size=chunk))
        labels = dict(coordinate=list(robot.coordinate_names), cable=list(robot.cable_names),
                      joint=list(robot.joint_names), component=list(COMPONENTS))
        for name, values in labels.items():
            values = np.array(values, dtype=str)
            _array(g, name, values, (name,), values.dtype.str, (max(len(values), 1),), None)
        units = coordinate_units(robot)
        g["q"].attrs["coordinate_units"] = units
        for coordinate, values in poses.axes:
            name = axis_name(coordinate)
            unit = units[list(robot.coordinate_names).index(coordinate)]
            _array(g, name, np.asarray(values, float), (name,), "f8", (len(values),), None,
                   dict(units=unit, description=f"grid axis: coordinate {coordinate}"))
        g.attrs["workspace"] = settings
        g.attrs["chunk_files"] = "every flagged chunk has one file per variable"
        zarr.consolidate_metadata(str(tmp))
        _rename_new(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _rename_new(tmp: Path, path: Path) -> None:
    """Move the finished store ``tmp`` to ``path``, which must not exist: a rename, atomic; where
    another run got there first, ``rename`` meets its non-empty folder and fails."""
    try:
        if path.exists():
            raise FileExistsError(path)
        os.rename(tmp, path)
    except OSError as exc:
        if path.exists():
            raise WorkspaceError(f"{path}: created by another run meanwhile; let that run finish, or give "
                                 f"--resume to complete its store, or another --out") from None
        raise WorkspaceError(f"{path}: cannot create the store ({exc.strerror or exc})") from None


def open_for_resume(path, settings: dict) -> tuple[list[int], dict[int, str]]:
    """The chunks of the store at ``path`` still to compute, and those among them that were flagged
    done but are damaged (:func:`damaged_chunks`; their flags are cleared); the store's settings must
    equal ``settings`` (same robot, problem, poses and chunk size)."""
    zarr = optional("zarr", "workspaces")

    path = Path(path)
    if not path.exists():
        raise WorkspaceError(f"{path}: no store to resume (run without --resume to create it)")
    try:
        g = zarr.open_group(str(path), mode="r+", zarr_format=2)
        old = g.attrs["workspace"]
    except Exception as exc:  # noqa: BLE001 - zarr raises several types for a foreign folder
        raise WorkspaceError(f"{path}: not a workspace store ({type(exc).__name__}: {exc})") from None
    if old != settings:
        keys = sorted(k for k in set(old) | set(settings) if old.get(k) != settings.get(k))
        raise WorkspaceError(f"{path}: made with other settings (differing: {', '.join(keys)}); resume with "
                             f"the command that created it, or write to another --out")
    for leftover in path.rglob("*.partial"):  # Zarr's temporary files of a write that was killed
        leftover.unlink(missing_ok=True)
    damaged = damaged_chunks(path, g)
    for k in damaged:
        g["chunk_done"][k] = 0  # computed again below
    done = g["chunk_done"][:]
    return [int(k) for k in np.flatnonzero(done == 0)], damaged


def _flags(path: Path, group) -> np.ndarray:
    try:
        return np.asarray(group["chunk_done"][:])
    except Exception as exc:  # noqa: BLE001 - a torn file: numcodecs, zarr and OSError alike
        raise WorkspaceError(f"{path}: the chunk_done flags cannot be read ({type(exc).__name__}: {exc}); "
                             f"the store is damaged") from None


def damaged_chunks(path, group=None) -> dict[int, str]:
    """The chunks flagged done that cannot be trusted: ``{chunk: what is wrong}``, where a variable's
    file is missing (stores that record ``chunk_files``) or does not decode."""
    zarr = optional("zarr", "workspaces")

    path = Path(path)
    group = zarr.open_group(str(path), mode="r", zarr_format=2) if group is None else group
    done = np.flatnonzero(_flags(path, group) == 1)
    whole = "chunk_files" in group.attrs
    bad: dict[int, str] = {}
    for name in RESULT_VARIABLES:
        array = group[name]
        size = array.chunks[0]
        if whole:
            tail = ".0" * (array.ndim - 1)
            for k in done:
                if k not in bad and not (path / name / f"{k}{tail}").is_file():
                    bad[int(k)] = f"{name}: its data is missing"
        per_chunk = max(array.nbytes // max(array.shape[0], 1) * size, 1)
        step = max(1, READ_BYTES // per_chunk)  # chunks per read: memory stays bounded
        for first in range(0, len(done), step):
            block = [int(k) for k in done[first:first + step] if int(k) not in bad]
            if not block:
                continue
            try:  # the common case: the block decodes in one read
                array[block[0] * size:(block[-1] + 1) * size]
                continue
            except Exception:  # noqa: BLE001 - find the chunk that does not decode
                pass
            for k in block:
                try:
                    array[k * size:(k + 1) * size]
                except Exception as exc:  # noqa: BLE001 - numcodecs, zarr and OSError alike
                    bad[k] = f"{name}: unreadable ({type(exc).__name__}: {exc})"
    return dict(sorted(bad.items()))


class Writer:
    """Writes chunks of results into an existing store, then flags them done."""

    def __init__(self, path, chunk: int):
        zarr = optional("zarr", "workspaces")

        self.group = zarr.open_group(str(path), mode="r+", zarr_format=2)
        whole = {"write_empty_chunks": True}  # a file per chunk, even of fill values: see damaged_chunks
        self.arrays = {name: self.group[name].with_config(whole) for name in RESULT_VARIABLES}
        self.done = self.group["chunk_done"]
        self.chunk = chunk

    def write(self, k: int, results: dict) -> None:
        start = k * self.chunk
        stop = start + len(results["status"])
        for name, array in self.arrays.items():
            array[start:stop] = results[name]
        self.done[k] = 1  # last: the chunk is complete


def open_workspace(path, check: bool = True):
    """The store as an ``xarray.Dataset`` (lazy, backed by Dask arrays). ``check``: first read every
    chunk flagged done (:func:`damaged_chunks`); an error names the store, chunk and variable that
    cannot be trusted."""
    xr = optional("xarray", "workspaces")

    path = Path(path)
    if not (path / ".zgroup").is_file():
        raise WorkspaceError(f"{path}: not a workspace store (no Zarr group there)")
    if check:
        bad = damaged_chunks(path)
        if bad:
            k, why = next(iter(bad.items()))
            more = f" (and {len(bad) - 1} more chunks)" if len(bad) > 1 else ""
            raise WorkspaceError(f"{path}: chunk {k} is flagged done but {why}{more}; run the "
                                 f"workspace command again with --resume to recompute it")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        ds = xr.open_zarr(str(path))
    if "workspace" not in ds.attrs:
        raise WorkspaceError(f"{path}: a Zarr store, but not one written by mcdm-pin workspace")
    return ds


def is_complete(ds) -> bool:
    return bool(np.all(ds["chunk_done"].values == 1))


def as_grid(ds):
    """A grid store with its poses unstacked onto the grid axes (dims ``axis1, axis2, ...`` instead of
    ``pose``); an error for random or file poses."""
    pd = optional("pandas", "workspaces")
    xr = optional("xarray", "workspaces")

    spec = ds.attrs["workspace"]["poses"]
    if spec["kind"] != "grid":
        raise WorkspaceError(f"the store's poses are {spec['kind']}, not a grid")
    names = [axis_name(a["coordinate"]) for a in spec["axes"]]
    index = pd.MultiIndex.from_product([ds[a].values for a in names], names=names)
    flat = ds.drop_vars(names).drop_dims("chunk")
    flat = flat.assign_coords(xr.Coordinates.from_pandas_multiindex(index, "pose"))
    return flat.unstack("pose")
