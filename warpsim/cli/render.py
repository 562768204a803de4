"""``warpsim render``: a recording drawn as a picture or an animation."""

from __future__ import annotations

from .._interrupt import interruptible
from .common import UsageError, number_type, size_type


def command(args) -> int:
    """Draw a recording as a PNG or an animated GIF."""
    from ..io.render import render_recording

    interruptible()  # the output's temporary is made next
    try:
        path = render_recording(
            args.recording, args.output, args.frame, args.size, args.azimuth, args.elevation, wide=args.wide
        )
    except RuntimeError as err:  # no Pillow (a bad recording or output: exit 2 in main._exit_code)
        raise UsageError(str(err)) from None
    print(f"{args.recording} -> {path}")
    return 0


def add_parser(sub) -> None:
    """Add the ``render`` command to the subparsers ``sub``."""
    render = sub.add_parser(
        "render",
        help="draw a recording as a picture (.png, one frame) or an animation (.gif)",
        description="Draw a recording with a small built-in renderer (needs Pillow: pip install -e '.[render]'): "
        "OUT.png shows one frame (default the last), OUT.gif the whole run at simulated speed. The camera looks "
        "from the side and a little above, under the sky, at the distance that frames the objects, and follows them.",
    )
    render.add_argument("recording", metavar="REC.h5")
    render.add_argument("output", metavar="OUT.png|OUT.gif")
    render.add_argument("--frame", type=int, help="frame to draw in a .png (default: the last; -1 = last)")
    render.add_argument("--size", type=size_type, default=(960, 540), metavar="WxH", help="pixels (default 960x540)")
    render.add_argument(
        "--azimuth",
        type=number_type("--azimuth", "an angle in degrees from -360 to 360", -360.0, 360.0, closed=True),
        default=-60.0,
        help="view direction about +z [deg] (default -60)",
    )
    render.add_argument(
        "--elevation",
        type=number_type("--elevation", "an angle in degrees from -90 to 90", -90.0, 90.0, closed=True),
        default=12.0,
        help="view height above the horizon [deg], -90..90 (default 12)",
    )
    render.add_argument(
        "--wide", action="store_true", help="frame the ropes and lines too (a kite's line down to its anchor)"
    )
