"""Does the kite fly centred as the time step shrinks? (issue 35) The default kite launched in 6 m/s with a 0.5°
crosswind, at several (dt, iterations): the tow point's sideways offset from the anchor and the line's elevation at
the anchor every 5 s.

    python -m benchmarks.validation.kite_side [--wind 6] [--crosswind 0.05] [--seconds 30] [--set KEY=VALUE ...]
        [DT/ITERATIONS ...]

A laterally stable, symmetric kite follows a 0.5° crosswind by its reach times the wind's angle (about 0.13 m);
the validation row "kite in 6 m/s, 0.5° crosswind, time step" reports the same runs. About 40 s on 2 cores for
the default rungs. Each line also gives the rung's ``sqrt(k) / dt``, ``k`` the plain Jacobi iterations its
iterations are worth (``cases.solver_stiffness``): with rigid sticks (``--set kite.sail_compliance=0 --set
kite.frame_compliance=0``, the paper's) the 6 m/s kite stays centred up to about 55k /s and goes to one side from about
58k /s, with or without Chebyshev acceleration; with elastic cloth on a rigid frame it stayed centred at these steps
for every cloth stiffness tried but those near 5e-5 m/N (4.999e-5 to 5.001e-5), which settled 1.6-1.9 m to one side
after ~15 s at 0.625 ms/220 and 0.3125 ms/110; with the frame elastic too (the defaults) it stays centred at every
rung (docs/objects.md).
"""

from __future__ import annotations

import argparse

from benchmarks.validation.kite_rows import KITE_CROSSWIND, KITE_CROSSWIND_STEPS, kite_crosswind_offset
from warpsim.scene.values import DescriptorError, parse_override


def _rung(text: str) -> tuple[float, int]:
    try:
        dt, iterations = text.split("/")
        return float(dt), int(iterations)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a rung is DT/ITERATIONS, e.g. 0.005/55, got {text!r}") from None


def main(argv: list[str] | None = None) -> int:
    """Entry point: one line per rung."""
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.validation.kite_side", description=__doc__.split("\n\n")[0].replace("\n", " ")
    )
    parser.add_argument("rungs", nargs="*", type=_rung, help="DT/ITERATIONS (default: the validation row's rungs)")
    parser.add_argument("--wind", type=float, default=6.0, help="wind along x [m/s] (default 6)")
    parser.add_argument("--crosswind", type=float, default=KITE_CROSSWIND, help="wind along y [m/s] (default 0.05)")
    parser.add_argument("--seconds", type=float, default=30.0, help="flight time [s] (default 30)")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a descriptor value of the kite's scene, e.g. --set kite.frame_mass_fraction=0.6 (repeatable)",
    )
    args = parser.parse_args(argv)
    overrides: dict = {}  # checked against the kite's scene when the first rung builds it
    for item in args.set:
        try:
            for section, values in parse_override(item).items():
                overrides.setdefault(section, {}).update(values)
        except DescriptorError as error:
            parser.error(str(error))
    if not args.wind > 0.0:
        parser.error(f"--wind is the wind along x the kite flies downwind of, and must be positive, got {args.wind:g}")
    if not (args.seconds >= 5.0 and args.seconds % 5.0 == 0.0):
        parser.error(f"--seconds must be a multiple of 5 (one sample every 5 s), got {args.seconds:g}")
    expected = None
    for dt, iterations in args.rungs or KITE_CROSSWIND_STEPS:
        try:
            r = kite_crosswind_offset(args.wind, args.crosswind, dt, iterations, args.seconds, overrides=overrides)
        except DescriptorError as error:  # a step, iteration count or wind the scene refuses: one line, no traceback
            parser.error(str(error))
        expected = r["expected"] if expected is None else expected  # the first rung's reach: centred, if any is
        track = " ".join(
            f"{5 * (k + 1)}s {o:+.2f} m/{a:.0f}°"
            for k, (o, a) in enumerate(zip(r["offsets"], r["angles"], strict=True))
        )
        print(
            f"dt {dt * 1000:g} ms/{iterations} (sqrt(k)/dt {r['stiffness'] / 1000:.1f}k /s): {track} "
            f"(a stable kite: {expected:+.2f} m)",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
