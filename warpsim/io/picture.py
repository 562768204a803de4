"""A picture output: the last frame of a run drawn as a PNG when it closes, with the small renderer of
``warpsim render`` (Pillow, the ``[render]`` extra)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .protocol import FrameOutput
from .render import Camera, Scene, _atomic_save, check_picture_path, require_pillow


class PictureOutput(FrameOutput):
    """Keep each frame's positions; :meth:`close` draws the last one to ``path`` (a ``.png``).

    Args:
        path: the PNG to write (checked now; written, whole or not at all, when the output closes).
        model: the run's :class:`~warpsim.physics.model.Model`.
        label: the name written in the picture's corner with the frame's time.
        size: ``(width, height)`` [pixels]. azimuth, elevation: the view direction [deg], as ``warpsim render``.
    """

    def __init__(self, path, model, label: str = "", size=(960, 540), azimuth: float = -60.0, elevation: float = 12.0):
        self.path = check_picture_path(path)
        if self.path.suffix.lower() != ".png":
            raise ValueError(f"{path}: a picture output writes a .png")
        require_pillow()
        self.scene, self.label = Scene(model), label
        self.camera = Camera(azimuth, elevation, size=tuple(size))
        self.last: tuple[float, np.ndarray] | None = None
        self.closed = False

    def log_state(self, frame) -> None:
        """Keep the frame's time and positions (the picture is drawn from the last one)."""
        self.last = (float(frame.time), np.array(frame.positions, copy=True))

    def close(self) -> Path | None:
        """Draw the last frame and write the PNG; returns its path (None when no frame came). Safe to call twice."""
        if self.closed or self.last is None:
            self.closed = True
            return self.path if self.last is not None else None
        self.closed = True
        time, q = self.last
        q = self.scene.place(q)  # the worlds side by side and the drawn points (pilot, pole) added
        camera = self.scene.fit([q], self.camera)
        image = self.scene.draw(q, camera, f"{self.label}  t = {time:.2f} s")
        return _atomic_save(self.path, lambda p: image.save(p, format="PNG"))
