r"""The paper's figure types from results files (matplotlib, Agg canvas; PNG and SVG).

Several runs (e.g. cases 1-3 on one trajectory) are drawn side by side, one column per run, on shared
axes (like the source paper's Figs. 6-16):

=======================  ==========================================================================
figure                   content
=======================  ==========================================================================
``cable_forces``         every cable's force over time, N
``interaction_forces``   one row per joint: the interaction force magnitude :math:`|F|`, N
``interaction_angles``   one row per spherical joint: the angle of :math:`F` from the socket axis,
                         degrees, with the cone half-angle :math:`\rho^*` as a dashed line (other
                         joints have no socket axis: the angle means nothing there and is not drawn;
                         a robot without spherical joints gets no such figure)
``trajectory``           the coordinates :math:`q` and their rates :math:`\dot q` (one column when
                         every run has the same trajectory)
``summary``              cable forces (top) and the angles of the joints that have a cone (bottom;
                         without cones, of the spherical joints)
=======================  ==========================================================================

Instants without a valid answer (``f`` is NaN there) are gaps in the lines, shaded red and marked with
a red ``x`` on the time axis. :math:`\rho^*` of a joint is the first run's cone on that joint that has
one, so a case-1 column shows the cone that case 3 enforces.

Use::

    from mcdm_pin.plots import plot_runs, save_figures
    figs = plot_runs([run1, run3], labels=["case 1", "case 3"])
    save_figures(figs, "figures")          # figures/cable_forces.png, .svg, ...
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .exceptions import McdmError, ResultsError
from .extras import optional

FIGURES = ("summary", "cable_forces", "interaction_forces", "interaction_angles", "trajectory")
FORMATS = ("png", "svg")
INFEASIBLE_COLOR = "#d62728"


class PlotError(McdmError, ValueError):
    """A figure cannot be drawn or written (unknown figure name or format, unwritable folder...)."""


# ------------------------------------------------------------------------------------------ input
def run_label(result, fallback: str = "run") -> str:
    """``case N`` when the run's problem string says so, else ``fallback``."""
    m = re.match(r"\s*(case \d)", str(getattr(result, "problem", "")))
    return m.group(1) if m else fallback


def check_compatible(runs, sources=None) -> None:
    """Raise :class:`ResultsError` unless all runs have the same joints and cables (so they can share
    axes)."""
    sources = sources or [f"run {k + 1}" for k in range(len(runs))]
    first = runs[0]
    for key in ("joint_names", "cable_names", "coordinate_names"):
        want = [str(x) for x in np.asarray(getattr(first, key)).tolist()]
        for run, src in zip(runs[1:], sources[1:]):
            got = [str(x) for x in np.asarray(getattr(run, key)).tolist()]
            if got != want:
                raise ResultsError(f"{src}: {key} {got} do not match those of {sources[0]} {want}; "
                                   f"runs drawn side by side must be of the same robot")


def load_runs(paths) -> list:
    """Load results ``.npz`` files (and check they can be drawn together)."""
    from .results import TrajectoryResult
    runs = []
    for p in paths:
        if Path(p).suffix != ".npz":
            raise ResultsError(f"{p}: expected a .npz results file (from mcdm-pin solve --out)")
        runs.append(TrajectoryResult.load(p))
    if not runs:
        raise ResultsError("no results file given")
    check_compatible(runs, [str(p) for p in paths])
    return runs


# -------------------------------------------------------------------------------------- helpers
def _new_figure(rows: int, cols: int, width_per_col=4.2, height_per_row=2.6, sharey="row"):
    FigureCanvasAgg = optional("matplotlib.backends.backend_agg", "the figures").FigureCanvasAgg
    Figure = optional("matplotlib.figure", "the figures").Figure
    fig = Figure(figsize=(1.2 + width_per_col * cols, 0.9 + height_per_row * rows), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, cols, sharex=True, sharey=sharey, squeeze=False)
    return fig, axes


def _colors(n: int):
    matplotlib = optional("matplotlib", "the figures")
    if n <= 10:
        cmap = matplotlib.colormaps["tab10"]
        return [cmap(i) for i in range(n)]
    if n <= 20:
        cmap = matplotlib.colormaps["tab20"]
        return [cmap(i) for i in range(n)]
    cmap = matplotlib.colormaps["turbo"]
    return [cmap(x) for x in np.linspace(0.02, 0.98, n)]


def infeasible_spans(t: np.ndarray, found: np.ndarray) -> list[tuple[float, float]]:
    """Time intervals (start, end) covering runs of instants without a valid answer, each widened by
    half a sample step on both sides."""
    t = np.asarray(t, float)
    bad = ~np.asarray(found, bool)
    spans = []
    k = 0
    while k < len(t):
        if bad[k]:
            j = k
            while j + 1 < len(t) and bad[j + 1]:
                j += 1
            lo = t[k] - (0.5 * (t[k] - t[k - 1]) if k > 0 else 0.0)
            hi = t[j] + (0.5 * (t[j + 1] - t[j]) if j + 1 < len(t) else 0.0)
            spans.append((float(lo), float(hi)))
            k = j + 1
        else:
            k += 1
    return spans


def _mark_infeasible(ax, run, labelled: list) -> None:
    found = run.found
    if np.all(found):
        return
    label = None if labelled else "no valid answer"
    for lo, hi in infeasible_spans(run.t, found):
        ax.axvspan(lo, hi, color=INFEASIBLE_COLOR, alpha=0.15, lw=0, label=label)
        label = None
    ax.plot(run.t[~found], np.zeros(int(np.sum(~found))), "x", color=INFEASIBLE_COLOR, ms=5,
            transform=ax.get_xaxis_transform(), clip_on=False, gid="infeasible-marks")
    labelled.append(True)


def angle_joints(runs) -> list[int]:
    """The joints whose interaction angle means something: those with a socket axis (spherical), from
    the runs' ``joint_types``. Files written before results carried the types: the joints with a cone
    in some run, or every joint when none has one (as before)."""
    types = getattr(runs[0], "joint_types", None)
    if types is not None and len(types) == len(runs[0].joint_names):
        return [j for j, kind in enumerate(np.asarray(types).tolist()) if kind == "spherical"]
    cones = _cone_lines(runs)
    with_cone = [j for j in range(len(cones)) if np.isfinite(cones[j])]
    return with_cone or list(range(len(cones)))


def _cone_lines(runs) -> np.ndarray:
    """rho* per joint: the first run's finite cone on that joint (NaN where none has one)."""
    out = np.full(len(runs[0].joint_names), np.nan)
    for run in runs:
        c = np.asarray(run.cone_deg, float)
        take = ~np.isfinite(out) & np.isfinite(c)
        out[take] = c[take]
    return out


def _titles(axes, labels) -> None:
    for ax, label in zip(axes[0], labels):
        ax.set_title(label)


def _legend(fig, axes, ncol_max=1) -> None:
    handles, names = [], []
    for ax in axes.flat:
        for h, n in zip(*ax.get_legend_handles_labels()):
            if n not in names:
                handles.append(h)
                names.append(n)
    if handles and len(handles) <= 24:
        fig.legend(handles, names, loc="outside right upper", fontsize="small",
                   ncol=1 if len(handles) <= 12 else 2)


def _draw_cable_forces(axes_row, runs) -> None:
    names = [str(n) for n in runs[0].cable_names]
    colors = _colors(len(names))
    labelled: list = []
    for ax, run in zip(axes_row, runs):
        for i, name in enumerate(names):
            ax.plot(run.t, run.f[:, i], color=colors[i], lw=1.2, label=name, gid=f"f:{name}")
        _mark_infeasible(ax, run, labelled)
        ax.grid(True, alpha=0.3)
    axes_row[0].set_ylabel("cable force, N")


def _draw_angles(axes, runs, joints) -> None:
    cones = _cone_lines(runs)
    labelled: list = []
    for r, j in enumerate(joints):
        name = str(runs[0].joint_names[j])
        for ax, run in zip(axes[r], runs):
            ax.plot(run.t, run.interaction_angle_deg[:, j], color="C0", lw=1.4, gid=f"angle:{name}")
            if np.isfinite(cones[j]):
                ax.axhline(cones[j], color="k", ls="--", lw=1.0, label=r"$\rho^*$",
                           gid=f"rho:{name}")
            _mark_infeasible(ax, run, labelled)
            ax.grid(True, alpha=0.3)
            ax.set_ylim(bottom=0)
        axes[r][0].set_ylabel(f"{name}: angle, deg")


# -------------------------------------------------------------------------------------- figures
def figure_cable_forces(runs, labels):
    fig, axes = _new_figure(1, len(runs), height_per_row=3.2)
    _draw_cable_forces(axes[0], runs)
    for ax in axes[-1]:
        ax.set_xlabel("t, s")
    _titles(axes, labels)
    _legend(fig, axes)
    fig.suptitle("Cable forces")
    return fig


def figure_interaction_forces(runs, labels):
    J = len(runs[0].joint_names)
    fig, axes = _new_figure(J, len(runs))
    labelled: list = []
    for j in range(J):
        name = str(runs[0].joint_names[j])
        for ax, run in zip(axes[j], runs):
            ax.plot(run.t, run.force_magnitude[:, j], color="C1", lw=1.4, label="|F|",
                    gid=f"F:{name}")
            _mark_infeasible(ax, run, labelled)
            ax.grid(True, alpha=0.3)
        axes[j][0].set_ylabel(f"{name}: |F|, N")
    for ax in axes[-1]:
        ax.set_xlabel("t, s")
    _titles(axes, labels)
    _legend(fig, axes)
    fig.suptitle("Interaction force magnitude per joint")
    return fig


def figure_interaction_angles(runs, labels):
    joints = angle_joints(runs)
    fig, axes = _new_figure(len(joints), len(runs))
    _draw_angles(axes, runs, joints)
    for ax in axes[-1]:
        ax.set_xlabel("t, s")
    _titles(axes, labels)
    _legend(fig, axes)
    fig.suptitle(r"Interaction force angle from the socket axis ($\rho^*$ dashed)")
    return fig


def figure_trajectory(runs, labels):
    same = all(np.array_equal(r.t, runs[0].t) and np.array_equal(r.q, runs[0].q) for r in runs[1:])
    shown = runs[:1] if same else runs
    names = [str(n) for n in runs[0].coordinate_names]
    colors = _colors(len(names))
    fig, axes = _new_figure(2, len(shown), width_per_col=5.0 if same else 4.2)
    for c, run in enumerate(shown):
        for i, name in enumerate(names):
            axes[0][c].plot(run.t, run.q[:, i], color=colors[i], lw=1.3, label=name, gid=f"q:{name}")
            axes[1][c].plot(run.t, run.qd[:, i], color=colors[i], lw=1.3, label=name,
                            gid=f"qd:{name}")
        for ax in axes[:, c]:
            ax.grid(True, alpha=0.3)
        axes[1][c].set_xlabel("t, s")
    axes[0][0].set_ylabel("q, rad (m)")
    axes[1][0].set_ylabel("qd, rad/s (m/s)")
    traj = runs[0].trajectory or "trajectory"
    _titles(axes, [traj] if same else labels)
    _legend(fig, axes)
    fig.suptitle("Trajectory: coordinates and their rates")
    return fig


def figure_summary(runs, labels):
    cones = _cone_lines(runs)
    joints = [j for j in range(len(cones)) if np.isfinite(cones[j])]
    if not joints:  # no cone anywhere: show the spherical joints' angles
        joints = angle_joints(runs)
    fig, axes = _new_figure(1 + len(joints), len(runs), height_per_row=2.6)
    _draw_cable_forces(axes[0], runs)
    _draw_angles(axes[1:], runs, joints)
    for ax in axes[-1]:
        ax.set_xlabel("t, s")
    _titles(axes, labels)
    _legend(fig, axes)
    traj = runs[0].trajectory
    fig.suptitle("Cable forces and interaction angles" + (f" ({traj})" if traj else ""))
    return fig


_BUILDERS = {"summary": figure_summary, "cable_forces": figure_cable_forces,
             "interaction_forces": figure_interaction_forces,
             "interaction_angles": figure_interaction_angles, "trajectory": figure_trajectory}


def plot_runs(runs, labels=None, figures=FIGURES) -> dict:
    """Draw ``figures`` (names from :data:`FIGURES`) for the runs, side by side.

    Args:
        runs: :class:`~mcdm_pin.results.TrajectoryResult` objects of one robot.
        labels: column titles (default: ``case N`` from each run's problem, else ``run k``).

    Returns:
        {figure name: matplotlib Figure} (without ``interaction_angles`` for a robot that has no
        spherical joint)
    """
    runs = list(runs)
    if not runs:
        raise ResultsError("no results to plot")
    check_compatible(runs)
    if labels is None:
        labels = [run_label(r, f"run {k + 1}") for k, r in enumerate(runs)]
    labels = [str(x) for x in labels]
    if len(labels) != len(runs):
        raise PlotError(f"labels: expected {len(runs)} labels (one per run), got {len(labels)}")
    unknown = [f for f in figures if f not in _BUILDERS]
    if unknown:
        raise PlotError(f"unknown figure {unknown[0]!r}; expected one of {', '.join(FIGURES)}")
    if not angle_joints(runs):  # no socket axis anywhere: no angle to draw
        figures = [f for f in figures if f != "interaction_angles"]
    return {name: _BUILDERS[name](runs, labels) for name in figures}


def save_figures(figs: dict, out_dir, formats=FORMATS, prefix: str = "", dpi: int = 130) -> list[Path]:
    """Write every figure as ``out_dir/<prefix><name>.<format>``; return the paths."""
    bad = [f for f in formats if f not in ("png", "svg", "pdf")]
    if bad:
        raise PlotError(f"format {bad[0]!r}: expected png, svg or pdf")
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise PlotError(f"{out}: cannot create the folder ({exc.strerror or exc})") from None
    paths = []
    for name, fig in figs.items():
        for fmt in formats:
            p = out / f"{prefix}{name}.{fmt}"
            try:
                fig.savefig(p, dpi=dpi)
            except OSError as exc:
                raise PlotError(f"{p}: cannot write the figure ({exc.strerror or exc})") from None
            paths.append(p)
    return paths


def plot_files(paths, out_dir, labels=None, figures=FIGURES, formats=FORMATS, prefix: str = "") -> list:
    """Load results files, draw the figures side by side and write them; return the written paths."""
    runs = load_runs(paths)
    if labels is None:
        labels = [run_label(r, Path(p).stem) for r, p in zip(runs, paths)]
    return save_figures(plot_runs(runs, labels, figures), out_dir, formats, prefix)


# ------------------------------------------------------------------------------------ workspace
STATUS_COLORS = {"optimal": "#2ca02c", "infeasible": "#bdbdbd", "softened": "#17becf",
                 "inaccurate": "#ff7f0e", "max_iter": "#9467bd", "error": "#000000"}


def figure_workspace(grid, title: str = ""):
    """Heat maps of a 2-D workspace grid (``mcdm_pin.workspace.as_grid`` of a store): the status of
    every pose, ``needed_f_max`` (N, the bound ``f_max`` as a black line) and, with cones,
    ``needed_cone_deg`` (degrees, the cone as a black line). Poses that no bound or no cone makes
    feasible (``inf``) are hatched."""
    ListedColormap = optional("matplotlib.colors", "the figures").ListedColormap
    Patch = optional("matplotlib.patches", "the figures").Patch

    attrs = grid.attrs["workspace"]
    axes_spec = [a for a in attrs["poses"]["axes"] if a["n"] > 1]
    if attrs["poses"]["kind"] != "grid" or len(axes_spec) != 2:
        raise PlotError("a workspace heat map needs a grid with exactly two axes of more than one "
                        f"point; this store has {attrs['poses']}")
    grid = grid.squeeze()
    ydim, xdim = grid["status"].dims
    x, y = grid[xdim].values, grid[ydim].values
    panels = ["status", "needed_f_max"] + (["needed_cone_deg"] if attrs["cones_deg"] else [])
    fig, axes = _new_figure(1, len(panels), width_per_col=4.4, height_per_row=3.8, sharey="row")
    status = grid["status"].values
    words = [w for w in STATUS_COLORS if (status == w).any()]
    codes = np.select([status == w for w in words], np.arange(len(words)), -1).astype(float)
    codes[codes < 0] = np.nan
    ax = axes[0][0]
    ax.pcolormesh(x, y, codes, cmap=ListedColormap([STATUS_COLORS[w] for w in words]),
                  vmin=-0.5, vmax=len(words) - 0.5, shading="nearest")
    ax.legend([Patch(color=STATUS_COLORS[w]) for w in words],
              [f"{w} ({int((status == w).sum())})" for w in words], fontsize="small", loc="upper right")
    ax.set_title("status")
    limits = {"needed_f_max": (float(min(attrs["f_max"])), "smallest common f_max, N"),
              "needed_cone_deg": (float(max(attrs["cones_deg"].values())) if attrs["cones_deg"] else 0.0,
                                  "smallest cone half-angle, deg")}
    for ax, name in zip(axes[0][1:], panels[1:]):
        value = grid[name].values
        finite = np.where(np.isfinite(value), value, np.nan)
        mesh = ax.pcolormesh(x, y, finite, cmap="viridis", shading="nearest",
                             norm="log" if name == "needed_f_max" and np.nanmin(finite) > 0 else None)
        if np.isinf(value).any():
            ax.contourf(x, y, np.isinf(value).astype(float), levels=[0.5, 1.5], colors="none",
                        hatches=["////"])
        limit, label = limits[name]
        if (value < limit).any() and (value > limit).any():
            big = 2.0 * max(np.nanmax(finite), limit)  # inf drawn beyond the line
            ax.contour(x, y, np.where(np.isinf(value), big, np.nan_to_num(finite, nan=big)),
                       levels=[limit], colors="k", linewidths=1.2)
        fig.colorbar(mesh, ax=ax, label=label)
        ax.set_title(f"{name} (line: {limit:g}; hatched: none)")
    units = dict(zip(grid["coordinate"].values, grid["q"].attrs.get("coordinate_units", [])))
    for ax in axes[0]:
        ax.set_xlabel(f"{xdim}, {units.get(xdim, grid[xdim].attrs.get('units', ''))}")
    axes[0][0].set_ylabel(f"{ydim}, {units.get(ydim, grid[ydim].attrs.get('units', ''))}")
    cones = ", ".join(f"{j} {d:g} deg" for j, d in attrs["cones_deg"].items())
    fig.suptitle(title or f"{attrs['robot']['name']}: {attrs['problem'].split(':')[0]}"
                          + (f", cones {cones}" if cones else "") + f"; {len(status.flat)} poses")
    return fig
