"""``warpsim plot``: a sweep's metric drawn as a line or a heat map, or a recording's figures against time."""

from __future__ import annotations

from .._interrupt import interruptible
from .common import UsageError


def command(args) -> int:
    """Draw a sweep's metric, or a recording's figures against time, as a PNG."""
    from ..sweeps.plot import plot_recording, plot_sweep

    recording = args.table.lower().endswith(".h5")
    if recording and (args.x or args.y or args.where):
        raise UsageError("a recording is drawn against time: --x, --y and --where are for a sweep's table")
    if not recording and not args.x:
        raise UsageError("--x KEY: the swept key on the horizontal axis of a sweep's table")
    interruptible()  # the output's temporary is made next
    if recording:  # PlotError: exit 2
        path = plot_recording(args.table, args.output, args.metric.split(","))
    else:
        path = plot_sweep(args.table, args.output, args.x, args.metric, args.y, args.where)
    print(f"{args.table} -> {path}")
    return 0


def add_parser(sub) -> None:
    """Add the ``plot`` command to the subparsers ``sub``."""
    plot = sub.add_parser(
        "plot",
        help="draw a metric of a sweep's table as a line or a heat map, or a recording's against time (PNG)",
        description="Draw a sweep's metric against one swept key (a line per combination of the other keys) or "
        "two (a heat map; the other keys fixed with --where). Blown-up cases are left out and counted in the "
        "title. A recording (REC.h5): its objects' figures against simulated time, one panel per --metric. "
        "Needs matplotlib (the sweep extra).",
    )
    plot.add_argument("table", metavar="SWEEP.parquet|SWEEP.csv|REC.h5")
    plot.add_argument("output", metavar="OUT.png")
    plot.add_argument("--x", metavar="KEY", help="swept key on the horizontal axis (a sweep's table: required)")
    plot.add_argument("--y", metavar="KEY", help="second swept key: draw a heat map")
    plot.add_argument(
        "--metric",
        required=True,
        metavar="M",
        help="the metric to draw, e.g. line_angle_mean; of a recording, against time, one or more: "
        "altitude,airspeed,sink (warpsim.sweeps.plot.recording_metrics)",
    )
    plot.add_argument(
        "--where",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="keep only the cases with this value of a swept key (repeatable)",
    )
