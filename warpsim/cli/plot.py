"""``warpsim plot``: a sweep's metric drawn as a line or a heat map."""

from __future__ import annotations

from .._interrupt import interruptible


def command(args) -> int:
    """Draw a sweep's metric as a PNG."""
    from ..sweeps.plot import plot_sweep

    interruptible()  # the output's temporary is made next
    path = plot_sweep(args.table, args.output, args.x, args.metric, args.y, args.where)  # PlotError: exit 2
    print(f"{args.table} -> {path}")
    return 0


def add_parser(sub) -> None:
    """Add the ``plot`` command to the subparsers ``sub``."""
    plot = sub.add_parser(
        "plot",
        help="draw a metric of a sweep's table as a line or a heat map (PNG)",
        description="Draw a sweep's metric against one swept key (a line per combination of the other keys) or "
        "two (a heat map; the other keys fixed with --where). Blown-up cases are left out and counted in the "
        "title. Needs matplotlib (the sweep extra).",
    )
    plot.add_argument("table", metavar="SWEEP.parquet|SWEEP.csv")
    plot.add_argument("output", metavar="OUT.png")
    plot.add_argument("--x", required=True, metavar="KEY", help="swept key on the horizontal axis")
    plot.add_argument("--y", metavar="KEY", help="second swept key: draw a heat map")
    plot.add_argument("--metric", required=True, metavar="M", help="the metric to draw, e.g. line_angle_mean")
    plot.add_argument(
        "--where",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="keep only the cases with this value of a swept key (repeatable)",
    )
