"""``mcdm-pin plot RESULTS.npz ... --out DIR``: the paper's figures from results files."""

from __future__ import annotations

from ._common import UsageError


def add(sub):
    from ..plots import FIGURES
    p = sub.add_parser("plot", help="the paper's figures (PNG + SVG) from results files, side by side")
    p.add_argument("results", nargs="+", help="results files (.npz), one column each (e.g. cases 1-3)")
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
    for p in plot_files(args.results, args.out, labels=labels, figures=figures, formats=formats,
                        prefix=args.prefix):
        print(f"wrote {p}")
    return 0
