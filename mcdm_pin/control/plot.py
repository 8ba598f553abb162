"""The figure of a control loop's run: the tracking error over time, and the cable tensions with the
ticks that fell back to the previous forces marked (``matplotlib``, the ``plots`` extra)."""

from __future__ import annotations

from pathlib import Path

from ..extras import optional


def plot_run(result, path, dpi: int = 100) -> Path:
    """Write ``result``'s figure (a :class:`~mcdm_pin.control.loop.LoopResult`) to ``path`` (PNG, SVG,
    ... by its suffix): above, the tracking error of the first physical joint (a platform's free joint:
    its position error in mm and its orientation error in degrees x 10); below, every cable's tension
    (N), with a red cross where a tick fell back to the previous tick's forces. Returns the path."""
    FigureCanvasAgg = optional("matplotlib.backends.backend_agg", "the control loop's figure").FigureCanvasAgg
    Figure = optional("matplotlib.figure", "the control loop's figure").Figure
    fig = Figure(figsize=(8, 6))
    FigureCanvasAgg(fig)
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    ax1.plot(result.t, result.error_lin_mm[:, 0], label="position error, mm")
    ax1.plot(result.t, result.error_rot_deg[:, 0] * 10, label="orientation error, deg x 10")
    ax1.set_ylabel("tracking error")
    ax1.legend()
    ax2.plot(result.t, result.f)
    late = result.fallback != ""
    if late.any():
        ax2.plot(result.t[late], result.f[late].max(axis=1), "rx", label="fallback (previous forces)")
        ax2.legend()
    ax2.set_xlabel("t, s")
    ax2.set_ylabel("cable tension, N")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path
