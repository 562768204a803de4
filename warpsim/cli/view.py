"""``warpsim view``: fly a scene in a live window."""

from __future__ import annotations

import contextlib
import sys

from .._interrupt import interruptible
from ..viewer.backend import ViewerUnavailableError, make_backend
from .common import (
    EXIT_BLOWUP,
    EXIT_INTERRUPTED,
    UsageError,
    add_scene_options,
    check_device,
    checked_output,
    load_scene,
    number_type,
    same_file_check,
    scene_sources,
    size_type,
)


def _on_display_lost(viewer, backend, shot):
    """Install an Xlib I/O error handler for when the X server goes away under the viewer (Xlib's own printed two
    lines and exited 1 with the recording open and no screenshot): close the recording with every frame flown, save
    the screenshot, say so in one line and exit 130. Returns the handler (keep it referenced), or None without
    Xlib."""
    import os

    try:
        from pyglet.libs.x11 import xlib
    except Exception:  # noqa: BLE001 - not X11 (or no pyglet): nothing to watch
        return None

    def lost(display):
        try:
            viewer.close_recording()
            saved = ""
            if shot is not None:
                from ..io.render import save_png

                saved = f"; screenshot: {save_png(shot, backend.screenshot())}"
            kept = f"; recording: {', '.join(str(p) for p in viewer.takes)}" if viewer.takes else ""
            sys.stderr.write(
                f"warpsim view: error: the display went away (its X server ended) at t = {viewer.sim.state.time:.2f} s"
                f"{kept}{saved}\n"
            )
            sys.stderr.flush()
        finally:
            os._exit(EXIT_INTERRUPTED)  # Xlib exits the process once this returns; nothing more can be drawn
        return 0

    handler = xlib.XIOErrorHandler(lost)
    xlib.XSetIOErrorHandler(handler)
    return handler


@contextlib.contextmanager
def _signals_quit(viewer):
    """Inside the block SIGINT and SIGTERM ask ``viewer`` to quit (its ``quit`` flag, read between frames), as Esc
    does. Off the main thread, signals are left alone."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handle(signum, frame):
        viewer.quit = True

    previous = {sig: signal.signal(sig, handle) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def command(args) -> int:
    """Fly a scene in a window until the user quits (or --seconds); print where the outputs went."""
    from ..io.hdf5 import RecordingError, check_recording_path
    from ..io.render import check_picture_path
    from ..run.simulation import Simulation, available_cores
    from ..viewer.core import Viewer

    browser = args.browser or args.host is not None or args.port is not None
    if browser and args.screenshot:
        raise UsageError(
            "--screenshot is for the window: with --browser the page is the picture (take it in the browser)"
        )
    h5_path = checked_output(check_recording_path, args.h5, "--h5")
    shot = checked_output(check_picture_path, args.screenshot, "--screenshot")
    if shot is not None:
        from ..io.render import require_pillow

        try:
            require_pillow()
        except RuntimeError as err:
            raise UsageError(f"--screenshot: {err}") from None
    device = check_device(args.device)
    scene, _ = load_scene(args)
    where = scene.where
    same_file_check(scene_sources(scene), {"--h5": h5_path, "--screenshot": shot}, "what the scene reads")
    if browser:
        port = 8765 if args.port is None else args.port
        options = {"host": args.host or "127.0.0.1", "port": port, "size": args.size}
    else:
        options = {"size": args.size, "keep_pictures": shot is not None}
    # a missing extra, display or port is said before the model is built
    backend = make_backend("browser" if browser else "window", **options)
    sim = Simulation(scene, device=device, where=where, threads=args.threads or available_cores())
    interruptible()  # the recording opens next
    try:
        viewer = Viewer(sim, backend, f"warpsim: {where}", h5_path, where, seconds=args.seconds)
    except RecordingError as err:
        raise UsageError(f"--h5 {err}") from None
    except ViewerUnavailableError as err:
        raise UsageError(f"--browser: {err}") from None
    if browser:
        return _serve(viewer, backend, sim)
    lost = _on_display_lost(viewer, backend, shot)  # kept referenced: Xlib holds only a C pointer to it
    # Ctrl-C in the terminal, or SIGTERM, quits like Esc, between two frames: the recording closed with every frame
    # flown (an interrupt raised between a step and its write once cost the frames since the last checkpoint), the
    # screenshot saved
    with _signals_quit(viewer), contextlib.suppress(KeyboardInterrupt):
        viewer.run()  # closes the recording and the window, however it ends
    if shot is not None:
        from ..io.render import save_png

        print(f"screenshot: {save_png(shot, backend.screenshot())}")
    del lost
    print(f"simulated {sim.state.time:.2f} s; drew {viewer.pictures} pictures")
    for path in viewer.takes:
        print(f"recording: {path}")
    return EXIT_BLOWUP if viewer.blew_up else 0


def _serve(viewer, backend, sim) -> int:
    """Fly ``viewer`` in the browser: print the page's address, wait for the first page, then fly at wall-clock
    pace until the pilot quits, --seconds, Ctrl-C or SIGTERM; the recording is closed however it ends."""
    from ..viewer.web import is_loopback

    print(f"open {backend.url} in a browser (Ctrl-C stops the server)", flush=True)
    if not backend.token and not is_loopback(backend.host):
        print("warning: no token is asked for on a non-loopback address", file=sys.stderr)
    waited = False
    with _signals_quit(viewer), contextlib.suppress(KeyboardInterrupt):
        try:
            while not viewer.quit:
                if not backend.clients:  # nobody watches: the flight waits (simulated time stands still)
                    print("no page connected: the flight waits for one" if waited else "waiting for a page", flush=True)
                    if not backend.wait_for_page(stop=lambda: viewer.quit):
                        break
                    print("a page connected: flying", flush=True)
                    viewer.hold_clock()
                    waited = True
                if not viewer.paced_tick():
                    break
        finally:
            viewer.close()  # the recording and the server, however it ends
    print(f"simulated {sim.state.time:.2f} s; sent {viewer.pictures} pictures to {backend.connections} page(s)")
    for path in viewer.takes:
        print(f"recording: {path}")
    return EXIT_BLOWUP if viewer.blew_up else 0


def add_parser(sub) -> None:
    """Add the ``view`` command to the subparsers ``sub``."""
    view = sub.add_parser(
        "view",
        help="fly a scene in a live 3-D window (keyboard control, real time)",
        description="Open a window and fly the scene at wall-clock pace: arrows steer the hang glider (held keys "
        "ramp pitch/roll to +-1, release ramps back), W/A/S/D walk the kite's anchor, +/- and [/] change the wind, "
        "Space pauses, '.' steps one frame, R restarts, C cycles the camera, H shows every key, Esc quits. "
        "Needs the viewer extra (pip install -e '.[viewer]') and a display (on a remote machine: ssh -X, or "
        "xvfb-run with --screenshot), or --browser to fly it in a web page instead.",
    )
    view.add_argument("scene", metavar="SCENE")
    add_scene_options(view)
    view.add_argument(
        "--h5",
        metavar="OUT.h5",
        help="record what is flown, with the controls as applied (replay: warpsim run --replay OUT.h5); after a "
        "restart the next take goes to OUT.take2.h5, ...",
    )
    view.add_argument(
        "--seconds", type=number_type("--seconds"), help="close after this much simulated time (default: when you quit)"
    )
    view.add_argument("--screenshot", metavar="OUT.png", help="save the last picture drawn as a PNG when closing")
    view.add_argument(
        "--browser",
        action="store_true",
        help="serve the flight to a web browser instead of opening a window: prints the page's address; the "
        "first page steers, later ones watch; the flight waits while no page is connected (needs the browser "
        "extra: pip install -e '.[browser]')",
    )
    view.add_argument(
        "--host",
        metavar="H",
        help="the browser view's address to listen on (implies --browser; default 127.0.0.1, this machine only; "
        "any other asks for the token printed in the page's address). From elsewhere, prefer "
        "ssh -L 8765:127.0.0.1:8765",
    )
    view.add_argument(
        "--port",
        type=int,
        metavar="N",
        help="the browser view's port to listen on (implies --browser; default 8765; 0: any free one)",
    )
    view.add_argument(
        "--size", type=size_type, default=(1280, 720), metavar="WxH", help="window size (default 1280x720)"
    )
