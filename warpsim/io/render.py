"""Preview pictures of a recording: one frame as a PNG, or an animated GIF (needs Pillow, the ``render`` extra).

A small software renderer, for a quick look without a USD viewer: a perspective camera looking at the objects
from the side and a little above (azimuth and elevation in degrees) at the distance that frames them, under a sky
whose colour goes from haze at the horizon to blue overhead, over the terrain shaded by its slope and fading into
haze with distance (grid lines every 10 m or more, so that motion over it shows), with the objects' shadows cast
straight down. Triangles are filled with their part's colour (the USD stage's) and shaded by a light from above,
drawn back to front (painter's algorithm); ropes and lines as polylines at least 2 pixels wide (a kite's line shows
at any distance), the tubes and bodies of :mod:`warpsim.objects.drawing` (a glider's keel and control frame, the pilot,
a flag's pole) as thick lines and discs. Virtual particles are not drawn. The camera follows the objects' centre
(with ``wide``, of everything drawn, ropes and lines too); its distance is fixed over the frames drawn, so sizes
compare between frames. The batch's worlds are drawn side by side (:func:`world_offsets`).

Files are written to a temporary name beside the target and renamed over it: complete or absent.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._extras import install_hint
from ..objects.drawing import shapes_for
from ..objects.style import COLOURS, SPHERE_PARTS
from . import OutputWriteError, check_output_path, create_temporary, reason

EXTENSIONS = (".png", ".gif")
SKY_TOP, SKY_HORIZON = np.array([0.42, 0.62, 0.90]), np.array([0.86, 0.91, 0.96])
HAZE_DISTANCE = 2500.0  # [m]: the ground's colour is halfway to the horizon's haze at 0.69 times this
LIGHT = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])  # towards the sun
GIF_FRAME = 0.05  # [s]: a GIF's frames are at least this far apart in simulated time (and played so)


def check_picture_path(path) -> Path:
    """Check that ``path`` is a .png or .gif in an existing directory (raises ``OutputPathError``)."""
    return check_output_path(path, EXTENSIONS, "picture")


def require_pillow():
    """Pillow's ``(Image, ImageDraw)``; ``RuntimeError`` with the install command when it is missing."""
    try:
        from PIL import Image, ImageDraw
    except ImportError:
        raise RuntimeError(f"pictures need Pillow: {install_hint('render')}") from None
    return Image, ImageDraw


def _font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.truetype("DejaVuSans.ttf", size)
    except OSError:
        return ImageFont.load_default()


@dataclass
class Camera:
    """A perspective view: ``azimuth`` [deg] from +x about +z of the direction from the target to the eye,
    ``elevation`` [deg] of the eye above the target's horizon, ``distance`` [m] from the target to the eye,
    vertical field of view ``fov`` [deg], ``size`` (width, height) [pixels]."""

    azimuth: float = -60.0
    elevation: float = 12.0
    distance: float = 20.0
    fov: float = 35.0
    size: tuple[int, int] = (960, 540)

    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit vectors ``(right, up, towards the viewer)`` of the view."""
        az, el = np.radians(self.azimuth), np.radians(self.elevation)
        back = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])  # from target to eye
        right = np.cross([0.0, 0.0, 1.0], back)
        right /= max(np.linalg.norm(right), 1e-12)
        return right, np.cross(back, right), back

    @property
    def focal(self) -> float:
        """Focal length [pixels]."""
        return 0.5 * self.size[1] / np.tan(np.radians(self.fov) / 2)

    def eye(self, target: np.ndarray) -> np.ndarray:
        """Where the camera is [m] when it looks at ``target``."""
        return np.asarray(target, dtype=np.float64) + self.distance * self.axes()[2]

    def project(self, points: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates ``[n, 2]`` and distance in front of the eye [m] (along the view; below 0: behind
        it) of world ``points`` ``[n, 3]`` seen with ``target`` in the middle of the picture."""
        right, up, back = self.axes()
        rel = np.asarray(points, dtype=np.float64) - self.eye(target)
        ahead = -(rel @ back)
        z = np.maximum(ahead, 1e-6)
        w, h = self.size
        f = self.focal
        return np.stack([w / 2 + f * (rel @ right) / z, h / 2 - f * (rel @ up) / z], axis=1), ahead


class Scene:
    """What to draw of a model: its triangles by part, curves, discs, tubes and the points they are drawn from.

    ``focus``: the objects' points (cloth, bodies, tubes); ``drawn``: those and the ropes and lines. The camera
    frames ``framed``: the focus (a kite fills the picture, its line runs down out of it), or with ``wide`` every
    drawn point (a kite's line down to its anchor).
    """

    def __init__(self, model, wide: bool = False):
        self.model = model
        self.shapes = shapes_for(model)
        self.triangles: list[tuple[np.ndarray, tuple]] = []  # (tri vertex ids [t,3], rgb)
        self.curves: list[tuple[np.ndarray, tuple]] = []
        self.discs: list[tuple[int, float, tuple]] = []  # (point, radius [m], rgb)
        self.tubes = list(self.shapes.tubes)  # (point a, point b, radius [m], rgb)
        self.offsets = None  # [W, 3] where each world is drawn [m], fixed by the first frame placed
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
                if part in self.shapes.hidden_parts:
                    continue
                for p in record.parts.get(part, []):
                    self.discs.append((int(p), radius, COLOURS[part]))
                    drawn.append(np.array([int(p)]))
        self.discs += list(self.shapes.balls)
        drawn += [self.shapes.tube_indices().ravel(), np.array([p for p, _, _ in self.shapes.balls], dtype=np.int64)]
        every = np.concatenate(drawn) if drawn else np.zeros(0, np.int64)
        self.drawn = np.unique(every) if len(every) else np.arange(model.particle_count)
        bodies = [t.ravel() for t, _ in self.triangles] + [np.array([p for p, _, _ in self.discs], dtype=np.int64)]
        bodies.append(self.shapes.tube_indices().ravel())
        bodies = np.concatenate(bodies)
        self.focus = np.unique(bodies) if len(bodies) else self.drawn  # the objects, not their ropes' ground ends
        self.framed = self.drawn if wide else self.focus  # what the camera frames and centres on

    def place(self, q: np.ndarray) -> np.ndarray:
        """Positions ``q`` ``[P, 3]`` [m] as drawn: each world moved to its place (the first ``q`` placed fixes
        the places), then the drawn points of :mod:`warpsim.objects.drawing` appended."""
        q = np.asarray(q)
        if self.model.world_count > 1:
            if self.offsets is None:
                self.offsets = world_offsets(self.model, q)
            q = q + self.offsets[self.model.particle_world_np].astype(q.dtype)
        return self.shapes.points(q)

    def fit(self, frames: list[np.ndarray], camera: Camera, margin: float = 0.12) -> Camera:
        """``camera`` at the distance that frames the :attr:`framed` points of every placed frame (each centred)."""
        right, up, back = camera.axes()
        w, h = camera.size
        ty = np.tan(np.radians(camera.fov) / 2) * (1 - 2 * margin)
        tx = ty * w / h
        distance = 1.0
        for q in frames:
            rel = q[self.framed] - self.centre(q)
            need = np.maximum(np.abs(rel @ right) / tx, np.abs(rel @ up) / ty) + rel @ back
            distance = max(distance, float(need.max()))
        return Camera(camera.azimuth, camera.elevation, distance, camera.fov, camera.size)

    def centre(self, q: np.ndarray) -> np.ndarray:
        """Centre of the :attr:`framed` points' bounding box [m] (``q``: placed positions)."""
        p = q[self.framed]
        return (p.min(axis=0) + p.max(axis=0)) / 2

    def _background(self, camera: Camera, eye: np.ndarray, image_mod):
        """Sky above the horizon, hazy ground below it (the terrain's mean height near the eye), per row."""
        w, h = camera.size
        f = camera.focal
        rows = np.arange(h) + 0.5
        angle = np.radians(-camera.elevation) + np.arctan((h / 2 - rows) / f)  # each row's ray above the horizon
        ground = float(self.model.terrain.height(eye[0], eye[1]))
        colour = np.empty((h, 3))
        up = angle > 0
        t = np.sqrt(np.clip(np.sin(angle[up]), 0, 1))[:, None]
        colour[up] = SKY_HORIZON * (1 - t) + SKY_TOP * t
        height = max(float(eye[2]) - ground, 0.5)
        reach = height / np.maximum(np.tan(-angle[~up]), 1e-6)  # horizontal distance to where the ray meets ground
        haze = (1 - np.exp(-reach / HAZE_DISTANCE))[:, None]
        flat = 0.55 + 0.45 * LIGHT[2]  # the shade of level ground (as _ground shades it)
        colour[~up] = np.asarray(COLOURS["terrain"]) * flat * (1 - haze) + SKY_HORIZON * 0.92 * haze
        return image_mod.fromarray(np.repeat((255 * colour)[:, None, :], w, axis=1).astype(np.uint8), "RGB")

    def draw(self, q: np.ndarray, camera: Camera, label: str = ""):
        """A PIL image of placed positions ``q`` ``[P + added, 3]`` (see :meth:`place`)."""
        image_mod, draw_mod = require_pillow()
        centre = self.centre(q)
        eye = camera.eye(centre)
        image = self._background(camera, eye, image_mod)
        pen = draw_mod.Draw(image)
        for quad, rgb, edge in self._ground(centre, eye, camera):
            pen.polygon([tuple(v) for v in quad], fill=rgb, outline=edge)
        self._shadows(q, centre, camera, image, image_mod, draw_mod)
        light = LIGHT
        near = 0.05
        items = []  # (distance ahead: far first, kind, payload)
        for ids, rgb in self.triangles:
            p = q[ids]  # [t, 3, 3]
            n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 1])
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
            shade = 0.45 + 0.55 * np.abs(n @ light)
            xy, ahead = camera.project(p.reshape(-1, 3), centre)
            xy, ahead = xy.reshape(-1, 3, 2), ahead.reshape(-1, 3)
            for k in np.flatnonzero(ahead.min(axis=1) > near):
                items.append((ahead[k].mean(), 0, (xy[k], tuple(np.asarray(rgb) * shade[k]))))
        for chain, rgb in self.curves:
            xy, ahead = camera.project(q[chain], centre)
            if ahead.min() > near:
                items.append((ahead.mean(), 1, (xy, rgb, 2)))
        for a, b, radius, rgb in self.tubes:
            xy, ahead = camera.project(q[[a, b]], centre)
            if ahead.min() > near:
                width = max(2, int(round(2 * radius * camera.focal / ahead.mean())))
                items.append((ahead.mean(), 1, (xy, rgb, width)))
        for p, radius, rgb in self.discs:
            xy, ahead = camera.project(q[p : p + 1], centre)
            if ahead[0] > near:
                items.append((ahead[0], 2, (xy[0], radius * camera.focal / ahead[0], rgb)))
        for _, kind, payload in sorted(items, key=lambda item: -item[0]):
            if kind == 0:
                xy, rgb = payload
                colour = tuple(int(255 * min(max(c, 0.0), 1.0)) for c in rgb)
                pen.polygon([tuple(v) for v in xy], fill=colour, outline=colour)
            elif kind == 1:
                xy, rgb, width = payload
                colour = tuple(int(255 * c) for c in rgb)
                pen.line([tuple(v) for v in xy], fill=colour, width=width, joint="curve")
                if width >= 5:  # a thick tube's ends rounded (a body, a harness)
                    r = (width - 1) / 2
                    for x, y in (xy[0], xy[-1]):
                        pen.ellipse([x - r, y - r, x + r, y + r], fill=colour)
            else:
                (x, y), r, rgb = payload
                r = max(r, 2.5)
                pen.ellipse([x - r, y - r, x + r, y + r], fill=tuple(int(255 * c) for c in rgb), outline=(40, 40, 40))
        if label:
            _panel(image, label, draw_mod)
        return image

    def _ground(self, centre: np.ndarray, eye: np.ndarray, camera: Camera, cells: int = 40):
        """The terrain around the point under the objects as quads in front of the eye: ``(xy [4, 2], rgb,
        outline rgb)``, far ones first, shaded by slope, hazy with distance; their edges are a grid of 10 m
        (or 20, 50, 100 m: the cells keep to ``cells`` a side)."""
        terrain = self.model.terrain
        half = max(60.0, 3.0 * float(np.linalg.norm(eye - centre)))
        cell = next((c for c in (10.0, 20.0, 50.0, 100.0, 200.0) if 2 * half / c <= cells), 500.0)
        x0 = np.floor((centre[0] - half) / cell) * cell
        y0 = np.floor((centre[1] - half) / cell) * cell
        n = int(np.ceil(2 * half / cell)) + 1
        xs, ys = x0 + cell * np.arange(n + 1), y0 + cell * np.arange(n + 1)
        gx, gy = np.meshgrid(xs, ys)
        gz = terrain.height(gx, gy)
        grid = np.stack([gx, gy, gz], axis=-1).reshape(-1, 3)
        xy, ahead = camera.project(grid, centre)
        xy, ahead = xy.reshape(n + 1, n + 1, 2), ahead.reshape(n + 1, n + 1)
        normal = terrain.normal(gx, gy)
        base = np.asarray(COLOURS["terrain"])
        light = LIGHT
        out = []
        w, h = camera.size
        for j in range(n):
            for i in range(n):
                a = ahead[j : j + 2, i : i + 2]
                if a.min() < 0.5:
                    continue
                quad = xy[[j, j, j + 1, j + 1], [i, i + 1, i + 1, i]]
                if (quad[:, 1] < 0).all() or (quad[:, 1] > h).all() or (quad[:, 0] < 0).all() or (quad[:, 0] > w).all():
                    continue
                reach = float(np.hypot(gx[j, i] - eye[0], gy[j, i] - eye[1]))
                haze = 1 - np.exp(-reach / HAZE_DISTANCE)
                shade = 0.55 + 0.45 * float(normal[j, i] @ light)
                rgb = base * shade * (1 - haze) + SKY_HORIZON * 0.92 * haze
                edge = rgb * (1 - 0.12 * (1 - haze))
                out.append((a.mean(), quad, tuple(int(255 * c) for c in rgb), tuple(int(255 * c) for c in edge)))
        out.sort(key=lambda item: -item[0])
        return [item[1:] for item in out]

    def _shadows(self, q, centre, camera, image, image_mod, draw_mod) -> None:
        """The objects' triangles cast straight down onto the terrain, darkening it by a third."""
        if not self.triangles:
            return
        mask = image_mod.new("L", image.size, 0)
        pen = draw_mod.Draw(mask)
        ids = np.concatenate([t for t, _ in self.triangles])
        p = q[ids].reshape(-1, 3).astype(np.float64)
        p[:, 2] = self.model.terrain.height(p[:, 0], p[:, 1]) + 0.02
        xy, ahead = camera.project(p, centre)
        xy, ahead = xy.reshape(-1, 3, 2), ahead.reshape(-1, 3)
        for k in np.flatnonzero(ahead.min(axis=1) > 0.5):
            pen.polygon([tuple(v) for v in xy[k]], fill=85)
        image.paste((30, 40, 25), (0, 0), mask)


def _panel(image, text: str, draw_mod) -> None:
    """``text`` in the top left corner on a dark semi-opaque panel."""
    overlay = draw_mod.Draw(image, "RGBA")
    font = _font(max(11, image.size[1] // 30))
    box = overlay.multiline_textbbox((12, 10), text, font=font)
    overlay.rectangle([box[0] - 8, box[1] - 6, box[2] + 8, box[3] + 6], fill=(20, 25, 35, 170))
    overlay.multiline_text((12, 10), text, font=font, fill=(255, 255, 255, 255))


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
    elevation: float = 12.0,
    max_frames: int = 400,
    wide: bool = False,
) -> Path:
    """Draw a recording: one frame (``frame``, default the last; negative counts from the end) to a .png,
    or the whole run to an animated .gif. A GIF draws every k-th frame, k the fewest frames that are at least
    :data:`GIF_FRAME` apart in simulated time (GIF players do not keep up with shorter ones) and that keep to
    ``max_frames``; each is shown for the simulated time between two drawn frames (rounded to GIF's 10 ms),
    so the GIF plays at simulated speed. ``azimuth`` and ``elevation`` [deg]: where the camera looks from; ``wide``:
    frame the ropes and lines too (:class:`Scene`).
    Returns the path written.
    """
    from .hdf5 import RecordingError
    from .recording import Recording

    output = check_picture_path(output)
    require_pillow()
    with Recording(recording_path) as recording:
        count = recording.frame_count
        if count == 0:
            raise RecordingError(f"{recording_path}: the recording has no frames")
        name = recording.recorded_scene().kind
        scene = Scene(recording.build_model(), wide)
        if output.suffix.lower() == ".png":
            k = count - 1 if frame is None else frame
            if not -count <= k < count:
                raise RecordingError(f"--frame {frame}: the recording has frames 0..{count - 1}")
            k %= count
            q = scene.place(recording.positions(k))
            camera = scene.fit([q], Camera(azimuth, elevation, size=size))
            image = scene.draw(q, camera, f"{name}  t = {recording.time[k]:.2f} s")
            return _atomic_save(output, lambda p: image.save(p, format="PNG"))
        stride = max(1, int(np.ceil(GIF_FRAME / recording.frame_interval - 1e-9)), -(-count // max_frames))
        ids = list(range(0, count, stride))
        frames = [scene.place(recording.positions(k)) for k in ids]
        camera = scene.fit(frames, Camera(azimuth, elevation, size=size))
        images = [
            scene.draw(q, camera, f"{name}  t = {recording.time[k]:.2f} s") for q, k in zip(frames, ids, strict=True)
        ]
        duration = max(20, 10 * int(round(100 * recording.frame_interval * stride)))
        return _atomic_save(
            output,
            lambda p: images[0].save(
                p, format="GIF", save_all=True, append_images=images[1:], duration=duration, loop=0
            ),
        )


def world_offsets(model, q: np.ndarray) -> np.ndarray:
    """Where each world of a batch is drawn, ``[W, 3]`` [m] added to its particles: the worlds of a batch start in
    the same place (they never touch each other), so pictures set them side by side, world 0 where it is and the
    others in a row along +y (more than four: a grid, rows along -x), spaced by 1.5 times a world's size at ``q``
    ``[P, 3]`` across the row and at least 0.3 times it along (a kite's line lies along) and 6 m, so that they do
    not overlap."""
    count = model.world_count
    if count <= 1:
        return np.zeros((max(count, 1), 3))
    mine = model.particle_world_np == 0
    extent = np.ptp(q[mine][:, :2], axis=0)
    along_y = max(1.5 * float(extent[1]), 0.3 * float(extent[0]), 6.0)
    along_x = max(1.5 * float(extent[0]), 6.0)
    columns = count if count <= 4 else int(np.ceil(np.sqrt(count)))
    k = np.arange(count)
    return np.stack([-(k // columns) * along_x, (k % columns) * along_y, np.zeros(count)], axis=1)
