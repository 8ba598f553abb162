"""``mcdm-pin plot RESULTS.npz ... --out DIR``: the paper's figures from results files."""

from __future__ import annotations

from pathlib import Path

from ._common import UsageError


def add(sub):
    from ..plots import FIGURES
    p = sub.add_parser("plot", help="the paper's figures (PNG + SVG) from results files, side by side; "
                                    "heat maps of a 2-D workspace grid (a .zarr store)")
    p.add_argument("results", nargs="+", help="results files (.npz), one column each (e.g. cases 1-3); "
                                              "or workspace stores (.zarr), one figure each")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--labels", help="column titles, comma-separated (default: 'case N' from each run)")
    p.add_argument("--figures", help=f"comma-separated subset of {','.join(FIGURES)} (default: all)")
    p.add_argument("--format", default="png,svg", help="comma-separated: png, svg, pdf (default png,svg)")
    p.add_argument("--prefix", default="", help="prefix of the file names")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    from ..plots import FIGURES, plot_files

    def items(text):
        return [x.strip() for x in text.split(",") if x.strip()]
    labels = items(args.labels) if args.labels else None
    if labels is not None and len(labels) != len(args.results):
        raise UsageError(f"--labels: expected {len(args.results)} labels (one per results file), "
                         f"got {len(labels)}")
    figures = items(args.figures) if args.figures else list(FIGURES)
    for f in figures:
        if f not in FIGURES:
            raise UsageError(f"--figures: unknown figure {f!r}; expected one of {', '.join(FIGURES)}")
    formats = items(args.format)
    for f in formats:
        if f not in ("png", "svg", "pdf"):
            raise UsageError(f"--format: unknown format {f!r}; expected png, svg or pdf")
    stores = [r for r in args.results if Path(r).is_dir()]
    if stores:
        if len(stores) != len(args.results) or args.figures or args.labels:
            raise UsageError("give either results files (.npz) or workspace stores (.zarr), and no "
                             "--figures or --labels with stores")
        return _plot_stores(stores, args.out, formats, args.prefix)
    for p in plot_files(args.results, args.out, labels=labels, figures=figures, formats=formats,
                        prefix=args.prefix):
        print(f"wrote {p}")
    return 0


def _plot_stores(stores, out, formats, prefix) -> int:
    from ..plots import figure_workspace, save_figures
    from ..workspace import as_grid, open_workspace

    for store in stores:
        fig = figure_workspace(as_grid(open_workspace(store)))
        for p in save_figures({Path(store).stem: fig}, out, formats, prefix):
            print(f"wrote {p}")
    return 0
