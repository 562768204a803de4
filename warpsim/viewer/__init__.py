"""The live viewer: ``warpsim view SCENE`` flies a scene in a window at wall-clock pace, by keyboard.

:class:`~warpsim.viewer.core.Viewer` holds everything that is not drawing: the simulation, the keyboard's
controls (through :meth:`warpsim.run.simulation.Simulation.set_controls`, the path schedules take), pacing, the
camera, the heads-up text, restarts, blow-ups and the ``--h5`` recording. It talks to a backend with a small
interface (:class:`~warpsim.viewer.backend.Backend`): :class:`~warpsim.viewer.backend.NullBackend` draws
nothing (tests, headless machines) and :class:`~warpsim.viewer.gl.PygletBackend` opens an OpenGL 3.3 window
with pyglet (the ``viewer`` extra), which runs on Mesa's software renderer as well as on a GPU: Warp's own
OpenGL renderer needs the CUDA driver, so it is not used; :class:`~warpsim.viewer.web.BrowserBackend` serves it
to a web page (the ``browser`` extra). :func:`~warpsim.viewer.backend.make_backend` makes one by name
(:data:`~warpsim.viewer.backend.BACKENDS`), after its own check of what it needs.
"""

from .backend import BACKENDS, Backend, NullBackend, ViewerUnavailableError, make_backend
from .core import Viewer
from .hud import KEYS

__all__ = ["BACKENDS", "KEYS", "Backend", "NullBackend", "Viewer", "ViewerUnavailableError", "make_backend"]
