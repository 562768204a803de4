"""``warpsim convert``: a recording written again as a USD stage."""

from __future__ import annotations

from .._interrupt import interruptible


def command(args) -> int:
    """Write a recording's frames as a USD stage."""
    from ..io.usd import recording_to_stage

    interruptible()  # the output's temporary is made next
    path = recording_to_stage(args.recording, args.output)  # a bad recording or output: exit 2 (main._exit_code)
    print(f"{args.recording} -> {path}")
    return 0


def add_parser(sub) -> None:
    """Add the ``convert`` command to the subparsers ``sub``."""
    convert = sub.add_parser(
        "convert",
        help="turn a recording into a USD stage",
        description="Write the frames of an HDF5 recording as an animated USD stage (same layout as run --usd).",
    )
    convert.add_argument("recording", metavar="REC.h5")
    convert.add_argument("output", metavar="OUT.usda|.usdc|.usdz")
