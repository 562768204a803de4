"""Preview pictures of a recording: one frame as a PNG, or an animated GIF (needs Pillow, the ``render`` extra).

A small software renderer, for a quick look without a USD viewer: an orthographic camera looking at the
objects from the side and a little above (azimuth and elevation in degrees), triangles filled with their
part's colour (the USD stage's) and shaded by a light from above, drawn back to front (painter's
algorithm); ropes and lines as polylines, the pilot or person as a disc, a patch of the terrain under the
objects as shaded quads. Virtual particles are not drawn. The camera follows the objects' centre; its
scale is fixed over the frames drawn, so sizes compare between frames.

Files are written to a temporary name beside the target and renamed over it: complete or absent.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import OutputWriteError, check_output_path, create_temporary, reason
from .style import COLOURS, SPHERE_PARTS

EXTENSIONS = (".png", ".gif")
SKY_TOP, SKY_BOTTOM = np.array([0.55, 0.72, 0.92]), np.array([0.88, 0.93, 0.98])


def check_picture_path(path) -> Path:
    """Check that ``path`` is a .png or .gif in an existing directory (raises ``OutputPathError``)."""
    return check_output_path(path, EXTENSIONS, "picture")


def require_pillow():
    """Pillow's ``(Image, ImageDraw)``; ``RuntimeError`` with the install command when it is missing."""
    try:
        from PIL import Image, ImageDraw
    except ImportError:
        raise RuntimeError("pictures need Pillow: pip install -e '.[render]' (or pip install pillow)") from None
    return Image, ImageDraw


@dataclass
class Camera:
    """An orthographic view: ``azimuth`` [deg] from +x about +z, ``elevation`` [deg] above the horizon,
    ``scale`` [pixels per metre], ``size`` (width, height) [pixels]."""

    azimuth: float = -60.0
    elevation: float = 20.0
    scale: float = 50.0
    size: tuple[int, int] = (960, 540)

    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit vectors ``(right, up, towards the viewer)`` of the view."""
        az, el = np.radians(self.azimuth), np.radians(self.elevation)
        back = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])  # from target to eye
        right = np.cross([0.0, 0.0, 1.0], back)
        right /= np.linalg.norm(right)
        return right, np.cross(back, right), back

    def project(self, points: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates ``[n, 2]`` and depth towards the viewer [m] of world ``points`` ``[n, 3]``."""
        right, up, back = self.axes()
        rel = points - centre
        w, h = self.size
        xy = np.stack([w / 2 + self.scale * rel @ right, h / 2 - self.scale * rel @ up], axis=1)
        return xy, rel @ back


class Scene:
    """What to draw of a model: its triangles by part, curves, discs and drawn particles."""

    def __init__(self, model):
        self.model = model
        self.triangles: list[tuple[np.ndarray, tuple]] = []  # (tri vertex ids [t,3], rgb)
        self.curves: list[tuple[np.ndarray, tuple]] = []
        self.discs: list[tuple[int, float, tuple]] = []  # (particle, radius [m], rgb)
        drawn = []
        tris = model.tri_indices.numpy().reshape(-1, 3)
        for record in model.objects:
            for part, ids in record.tri_parts.items():
                self.triangles.append((tris[np.asarray(ids, dtype=np.int64)], COLOURS.get(part, (0.7, 0.7, 0.7))))
                drawn.append(tris[np.asarray(ids, dtype=np.int64)].ravel())
            for part, chains in record.curves.items():
                for chain in chains:
                    self.curves.append((np.asarray(chain, dtype=np.int64), COLOURS.get(part, (0.2, 0.2, 0.2))))
                    drawn.append(np.asarray(chain, dtype=np.int64))
            for part, radius in SPHERE_PARTS.items():
                for p in record.parts.get(part, []):
                    self.discs.append((int(p), radius, COLOURS[part]))
                    drawn.append(np.array([int(p)]))
        self.drawn = np.unique(np.concatenate(drawn)) if drawn else np.arange(model.particle_count)

    def fit(self, frames: list[np.ndarray], camera: Camera, margin: float = 0.15) -> Camera:
        """``camera`` with the scale that fits the drawn particles of every frame (each centred) in the image."""
        extent = np.zeros(2)
        for q in frames:
            p = q[self.drawn]
            xy, _ = Camera(camera.azimuth, camera.elevation, 1.0, (0, 0)).project(p, self.centre(q))
            extent = np.maximum(extent, 2 * np.abs(xy).max(axis=0))
        w, h = camera.size
        scale = min(w * (1 - 2 * margin) / max(extent[0], 1e-3), h * (1 - 2 * margin) / max(extent[1], 1e-3))
        return Camera(camera.azimuth, camera.elevation, float(scale), camera.size)

    def centre(self, q: np.ndarray) -> np.ndarray:
        """Centre of the drawn particles' bounding box [m]."""
        p = q[self.drawn]
        return (p.min(axis=0) + p.max(axis=0)) / 2

    def draw(self, q: np.ndarray, camera: Camera, label: str = ""):
        """A PIL image of positions ``q`` ``[N, 3]``."""
        image_mod, draw_mod = require_pillow()
        w, h = camera.size
        t = np.linspace(0.0, 1.0, h)[:, None]
        sky = (SKY_TOP * (1 - t) + SKY_BOTTOM * t) * 255
        image = image_mod.fromarray(np.repeat(sky[:, None, :], w, axis=1).astype(np.uint8), "RGB")
        pen = draw_mod.Draw(image)
        centre = self.centre(q)
        _, _, back = camera.axes()
        light = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
        items = []  # (depth, kind, payload)
        for poly, rgb in self._ground(q, centre, camera):
            items.append((poly[1], "poly", (poly[0], rgb)))
        for ids, rgb in self.triangles:
            p = q[ids]  # [t, 3, 3]
            n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 1])
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
            shade = 0.45 + 0.55 * np.abs(n @ light)
            xy, depth = camera.project(p.reshape(-1, 3), centre)
            xy, depth = xy.reshape(-1, 3, 2), depth.reshape(-1, 3).mean(axis=1)
            for k in range(len(ids)):
                items.append((depth[k], "poly", (xy[k], tuple(np.asarray(rgb) * shade[k]))))
        for chain, rgb in self.curves:
            xy, depth = camera.project(q[chain], centre)
            items.append((depth.mean(), "line", (xy, rgb)))
        for p, radius, rgb in self.discs:
            xy, depth = camera.project(q[p : p + 1], centre)
            items.append((depth[0], "disc", (xy[0], radius * camera.scale, rgb)))
        for _, kind, payload in sorted(items, key=lambda item: item[0]):
            if kind == "poly":
                xy, rgb = payload
                colour = tuple(int(255 * min(max(c, 0.0), 1.0)) for c in rgb)
                pen.polygon([tuple(v) for v in xy], fill=colour, outline=colour)
            elif kind == "line":
                xy, rgb = payload
                pen.line([tuple(v) for v in xy], fill=tuple(int(255 * c) for c in rgb), width=2)
            else:
                (x, y), r, rgb = payload
                r = max(r, 3.0)
                pen.ellipse([x - r, y - r, x + r, y + r], fill=tuple(int(255 * c) for c in rgb), outline=(40, 40, 40))
        if label:
            pen.text((10, 10), label, fill=(20, 20, 20))
        return image

    def _ground(self, q: np.ndarray, centre: np.ndarray, camera: Camera, cells: int = 24):
        """Shaded quads of the terrain around the objects: ``((xy [4,2], depth), rgb)``."""
        terrain = self.model.terrain
        half = 0.5 * max(camera.size) / camera.scale * 4.0
        xs = np.linspace(centre[0] - half, centre[0] + half, cells + 1)
        ys = np.linspace(centre[1] - half, centre[1] + half, cells + 1)
        gx, gy = np.meshgrid(xs, ys)
        gz = terrain.height(gx, gy)
        grid = np.stack([gx, gy, gz], axis=-1)
        xy, depth = camera.project(grid.reshape(-1, 3), centre)
        xy, depth = xy.reshape(cells + 1, cells + 1, 2), depth.reshape(cells + 1, cells + 1)
        normal = terrain.normal(gx, gy)
        base = np.asarray(COLOURS["terrain"])
        out = []
        for j in range(cells):
            for i in range(cells):
                quad = xy[[j, j, j + 1, j + 1], [i, i + 1, i + 1, i]]
                if (quad[:, 1] < 0).all() or (quad[:, 1] > camera.size[1]).all():
                    continue
                shade = 0.6 + 0.4 * normal[j, i, 2] * (0.92 if (i + j) % 2 else 1.0)
                out.append(((quad, depth[j : j + 2, i : i + 2].mean() - 1e6), base * shade))  # always behind
        return out


def _atomic_save(path: Path, save) -> Path:
    """Call ``save(temporary name)`` and rename the result over ``path``; a failure (full disk) leaves ``path``
    as it was and raises :class:`warpsim.io.OutputWriteError`."""
    tmp = None
    try:
        try:
            tmp, fd = create_temporary(path)  # our own regular file: a link planted there is removed, not followed
            os.close(fd)
            save(tmp)
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
        except OSError as err:
            raise OutputWriteError(f"{path}: could not write the picture ({reason(err)})") from None
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, path)
    finally:
        if tmp is not None:
            tmp.unlink(missing_ok=True)
    return path


def save_png(path, pixels: np.ndarray) -> Path:
    """Write ``[height, width, 3]`` uint8 ``pixels`` (top row first) to the .png ``path``, complete or not at all."""
    image_mod, _ = require_pillow()
    image = image_mod.fromarray(np.asarray(pixels, dtype=np.uint8), "RGB")
    return _atomic_save(Path(path), lambda p: image.save(p, format="PNG"))


def render_recording(
    recording_path,
    output,
    frame: int | None = None,
    size: tuple[int, int] = (960, 540),
    azimuth: float = -60.0,
    elevation: float = 20.0,
    max_frames: int = 150,
) -> Path:
    """Draw a recording: one frame (``frame``, default the last; negative counts from the end) to a .png,
    or the whole run to an animated .gif (every k-th frame so that at most ``max_frames`` are drawn, played
    at the simulated speed). Returns the path written.
    """
    from .hdf5 import RecordingError
    from .recording import Recording

    output = check_picture_path(output)
    require_pillow()
    with Recording(recording_path) as recording:
        count = recording.frame_count
        if count == 0:
            raise RecordingError(f"{recording_path}: the recording has no frames")
        descriptor = recording.descriptor()
        scene = Scene(recording.build_model())
        name = descriptor["scene"]["object"]
        if output.suffix.lower() == ".png":
            k = count - 1 if frame is None else frame
            if not -count <= k < count:
                raise RecordingError(f"--frame {frame}: the recording has frames 0..{count - 1}")
            k %= count
            q = recording.positions(k)
            camera = scene.fit([q], Camera(azimuth, elevation, 1.0, size))
            image = scene.draw(q, camera, f"{name}  t = {recording.time[k]:.2f} s")
            return _atomic_save(output, lambda p: image.save(p, format="PNG"))
        stride = max(1, -(-count // max_frames))
        ids = list(range(0, count, stride))
        frames = [recording.positions(k) for k in ids]
        camera = scene.fit(frames, Camera(azimuth, elevation, 1.0, size))
        images = [
            scene.draw(q, camera, f"{name}  t = {recording.time[k]:.2f} s") for q, k in zip(frames, ids, strict=True)
        ]
        duration = max(20, int(round(1000 * recording.frame_interval * stride)))
        return _atomic_save(
            output,
            lambda p: images[0].save(
                p, format="GIF", save_all=True, append_images=images[1:], duration=duration, loop=0
            ),
        )
