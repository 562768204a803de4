"""Animated USD stages of a run, for external viewers (usdview, Blender, Omniverse).

Layout: stage metadata ``upAxis = Z``, ``metersPerUnit = 1``, ``timeCodesPerSecond`` = the frame rate
(one time code per output frame, frame ``k`` at time code ``k``), start/end time codes; ``/World`` is the
default prim. ``/World/Terrain`` is a static mesh of the heightfield (at most ``STAGE_TERRAIN_SIDE`` samples a
side). Each object is an Xform ``/World/<object>`` holding:

* one Mesh per triangle part (sail, keel, canopy, cloth): topology written once, ``points`` and
  ``extent`` time-sampled at every frame;
* ``BasisCurves`` (linear) for its ropes and lines, with constant widths and time-sampled points;
* a Sphere per heavy point (pilot, person) with a time-sampled translate.

Virtual particles (the frame's helpers) are not drawn. Display colours tell the parts apart.

The stage is built in memory and exported when the run ends (also on Ctrl-C/SIGTERM): first to a
temporary file beside the target (``.NAME.PID.tmp.EXT``), which is synced, opened again and checked,
then renamed over the target, so a viewer never sees a half-written stage, a failed export (a full disk)
leaves the target as it was, and a run killed outright leaves no file under the target's name (its
temporary is removed by the next export there). ``.usdz`` packages a ``.usdc`` layer.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdUtils, Vt

from ..objects.style import COLOURS, CURVE_WIDTH, SPHERE_PARTS
from . import (
    OutputWriteError,
    cause,
    check_stage_path,
    create_temporary,
    with_disk_state,
)
from .protocol import FrameOutput


def _vec3f_array(points: np.ndarray) -> Vt.Vec3fArray:
    # USD points are float32: a coordinate beyond its range (a recording of a blow-up) is written as +-inf
    with np.errstate(over="ignore"):
        return Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(points, dtype=np.float32))


def _extent(points: np.ndarray) -> Vt.Vec3fArray:
    return Vt.Vec3fArray([Gf.Vec3f(*map(float, points.min(axis=0))), Gf.Vec3f(*map(float, points.max(axis=0)))])


def _colour(prim, part: str) -> None:
    rgb = COLOURS.get(part, (0.7, 0.7, 0.7))
    UsdGeom.Gprim(prim).CreateDisplayColorAttr(Vt.Vec3fArray([Gf.Vec3f(*rgb)]))


def _prim_name(text: str) -> str:
    name = "".join(c if c.isalnum() or c == "_" else "_" for c in text)
    return name if name and not name[0].isdigit() else f"_{name}"


STAGE_TERRAIN_SIDE = 1025
"""The most terrain samples a side that a stage draws (the simulation itself uses every one)."""


def _samples(count: int, most: int) -> np.ndarray:
    """Indices of at most ``most`` evenly spread samples of ``count``, the first and the last among them."""
    if count <= most:
        return np.arange(count)
    return np.unique(np.round(np.linspace(0, count - 1, most)).astype(np.int64))


class UsdWriter(FrameOutput):
    """Write the frames of a run as an animated USD stage.

    Args:
        path: output ``.usda``, ``.usdc`` or ``.usdz`` (checked by :func:`check_stage_path`).
        model: the :class:`warpsim.Model` (its objects' parts, triangles and curves say what to draw).
        frame_interval: simulated time between frames [s]; ``timeCodesPerSecond = 1 / frame_interval``.

    Call :meth:`write` with each frame's time and positions, then :meth:`close` (which exports). The time
    code of a frame at time ``t`` is ``t / frame_interval``: whole numbers on the frame grid (a run's
    shorter last frame falls between two).
    """

    def __init__(self, path, model, frame_interval: float):
        self.path = check_stage_path(path)
        self.model = model
        self.frame_interval = float(frame_interval)
        self.stage = Usd.Stage.CreateInMemory()
        stage = self.stage
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        fps = 1.0 / float(frame_interval)
        stage.SetTimeCodesPerSecond(fps)
        stage.SetFramesPerSecond(fps)
        world = UsdGeom.Xform.Define(stage, "/World")
        stage.SetDefaultPrim(world.GetPrim())
        stage.GetRootLayer().customLayerData = {"creator": "warpsim"}
        self._terrain(model.terrain)
        self.meshes: list[tuple[UsdGeom.Mesh, np.ndarray]] = []  # mesh, particle ids of its points
        self.curves: list[tuple[UsdGeom.BasisCurves, np.ndarray]] = []
        self.spheres: list[tuple[Usd.Prim, int, UsdGeom.XformOp]] = []
        for record in model.objects:
            self._object(record)
        self.first: int | None = None
        self.last: int | None = None
        self.closed = False

    def _terrain(self, terrain) -> None:
        # a picture of the ground, sampled to at most STAGE_TERRAIN_SIDE points a side (every edge sample kept): an
        # 8192^2 terrain grew a stage past 6 GB and ended in a MemoryError
        rows, cols = (_samples(n, STAGE_TERRAIN_SIDE) for n in terrain.heights.shape)
        ny, nx = len(rows), len(cols)
        xs = terrain.origin[0] + terrain.cell[0] * cols
        ys = terrain.origin[1] + terrain.cell[1] * rows
        gx, gy = np.meshgrid(xs, ys)
        points = np.stack([gx, gy, terrain.heights[np.ix_(rows, cols)]], axis=-1).reshape(-1, 3)
        i = np.arange(ny - 1)[:, None] * nx + np.arange(nx - 1)[None, :]
        quads = np.stack([i, i + 1, i + nx + 1, i + nx], axis=-1).reshape(-1)
        mesh = UsdGeom.Mesh.Define(self.stage, "/World/Terrain")
        mesh.CreatePointsAttr(_vec3f_array(points))
        mesh.CreateExtentAttr(_extent(points))
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full((ny - 1) * (nx - 1), 4, dtype=np.int32)))
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(quads.astype(np.int32)))
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        _colour(mesh.GetPrim(), "terrain")

    def _object(self, record) -> None:
        stage, model = self.stage, self.model
        root = f"/World/{_prim_name(record.name)}"
        UsdGeom.Xform.Define(stage, root)
        for part, tri_ids in record.tri_parts.items():
            tris = model.tri_indices_np[np.asarray(tri_ids, dtype=np.int64)]
            ids, local = np.unique(tris.reshape(-1), return_inverse=True)
            mesh = UsdGeom.Mesh.Define(stage, f"{root}/{_prim_name(part)}")
            mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(tris), 3, dtype=np.int32)))
            mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(local.astype(np.int32)))
            mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
            mesh.CreateDoubleSidedAttr(True)
            mesh.CreatePointsAttr()
            mesh.CreateExtentAttr()
            _colour(mesh.GetPrim(), part)
            self.meshes.append((mesh, ids))
        for part, chains in record.curves.items():
            chains = [np.asarray(c, dtype=np.int64) for c in chains]
            curves = UsdGeom.BasisCurves.Define(stage, f"{root}/{_prim_name(part)}")
            curves.CreateTypeAttr(UsdGeom.Tokens.linear)
            curves.CreateCurveVertexCountsAttr(Vt.IntArray([len(c) for c in chains]))
            curves.CreateWidthsAttr(Vt.FloatArray([CURVE_WIDTH.get(part, 0.02)]))
            curves.SetWidthsInterpolation(UsdGeom.Tokens.constant)
            curves.CreatePointsAttr()
            curves.CreateExtentAttr()
            _colour(curves.GetPrim(), part)
            self.curves.append((curves, np.concatenate(chains)))
        for part, radius in SPHERE_PARTS.items():
            for k, p in enumerate(record.parts.get(part, [])):
                name = _prim_name(part) if k == 0 else f"{_prim_name(part)}_{k}"
                sphere = UsdGeom.Sphere.Define(stage, f"{root}/{name}")
                sphere.CreateRadiusAttr(radius)
                sphere.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(-radius), Gf.Vec3f(radius)]))
                _colour(sphere.GetPrim(), part)
                op = sphere.AddTranslateOp()
                self.spheres.append((sphere.GetPrim(), int(p), op))

    def time_code(self, time: float) -> float:
        """Time code of simulated ``time`` [s] (frame grid points are whole numbers)."""
        code = time / self.frame_interval
        return float(round(code)) if abs(code - round(code)) < 1e-6 else code

    def write(self, time: float, positions: np.ndarray) -> None:
        """Time-sample every drawn part at simulated ``time`` [s] from ``positions`` ``[particle_count, 3]`` [m]."""
        index = self.time_code(time)
        t = Usd.TimeCode(index)
        for mesh, ids in self.meshes:
            pts = positions[ids]
            mesh.GetPointsAttr().Set(_vec3f_array(pts), t)
            mesh.GetExtentAttr().Set(_extent(pts), t)
        for curves, ids in self.curves:
            pts = positions[ids]
            curves.GetPointsAttr().Set(_vec3f_array(pts), t)
            curves.GetExtentAttr().Set(_extent(pts), t)
        for _, p, op in self.spheres:
            op.Set(Gf.Vec3d(*map(float, positions[p])), t)
        self.first = index if self.first is None else min(self.first, index)
        self.last = index if self.last is None else max(self.last, index)

    def log_state(self, frame) -> None:
        """The :class:`~warpsim.io.protocol.Output` step: :meth:`write` the frame's time and positions."""
        self.write(frame.time, frame.positions)

    def close(self) -> Path | None:
        """Export the stage atomically to :attr:`path`; returns it (None when no frame was written).

        Raises :class:`warpsim.io.OutputWriteError` (one line) when the stage cannot be written or does not
        open again; the target is then left as it was.
        """
        if self.closed:
            return self.path
        self.closed = True
        if self.first is None:
            return None
        self.stage.SetStartTimeCode(self.first)
        self.stage.SetEndTimeCode(self.last)
        umask = os.umask(0)
        os.umask(umask)
        tmp = None
        try:
            with _stderr_captured() as captured:
                try:
                    tmp, fd = create_temporary(self.path)  # our own regular file: a planted link is removed
                    os.close(fd)
                    self._export(tmp)
                    _check_stage(tmp)
                except Exception as err:  # noqa: BLE001 - USD reports write errors as several exception types
                    detail = with_disk_state(cause(f"{captured()}\n{err}"), self.path)
                    raise OutputWriteError(
                        f"{self.path}: could not write the stage ({detail}); nothing was written under that name"
                    ) from None
            os.chmod(tmp, 0o666 & ~umask)  # an ordinary output file
            os.replace(tmp, self.path)
        finally:
            if tmp is not None:
                tmp.unlink(missing_ok=True)
        return self.path

    def _export(self, tmp: Path) -> None:
        """Write the stage to ``tmp`` and sync it to disk; a .usdz packages a ``STEM.usdc`` layer written to a
        private temporary directory first."""
        if self.path.suffix.lower() == ".usdz":
            with tempfile.TemporaryDirectory() as scratch:
                layer = Path(scratch) / f"{self.path.stem}.usdc"
                if not self.stage.GetRootLayer().Export(str(layer)):
                    raise OSError("the layer export failed")
                if not UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(layer)), str(tmp)):
                    raise OSError("packaging failed")
        elif not self.stage.GetRootLayer().Export(str(tmp)):
            raise OSError("the export failed")
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())  # a full disk can show up only here (delayed allocation)


def _check_stage(path: Path) -> None:
    """Raise ``OSError`` unless the stage file at ``path`` is whole: a .usdz's members pass their CRC check, and
    the stage opens with its ``/World`` prim."""
    if path.suffix.lower() == ".usdz":
        with zipfile.ZipFile(path) as package:
            bad = package.testzip()
            if bad is not None:
                raise OSError(f"member {bad} of the package is damaged")
    stage = Usd.Stage.Open(str(path), Usd.Stage.LoadNone)
    if stage is None or not stage.GetPrimAtPath("/World"):
        raise OSError("the written stage does not open")


@contextlib.contextmanager
def _stderr_captured():
    """Send what USD prints to the process's stderr (fd 2) to a temporary file inside the block; yields a function
    returning the first 64 KiB of it (USD can print thousands of lines about one failed write)."""
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr at all
        yield lambda: ""
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)

        def printed() -> str:
            try:
                sink.seek(0)
                text = sink.read(65536).decode("utf-8", "replace")
            except OSError:
                return ""
            return text

        try:
            yield printed
        finally:
            os.dup2(saved, 2)
            os.close(saved)


def recording_to_stage(recording_path, output) -> Path:
    """Write the frames of the HDF5 recording at ``recording_path`` as the stage ``output`` (same layout and
    time codes as a direct export); returns its path. Raises ``RecordingError`` for a recording without frames."""
    from .hdf5 import RecordingError
    from .recording import Recording

    check_stage_path(output)
    with Recording(recording_path) as recording:
        if recording.frame_count == 0:
            raise RecordingError(f"{recording_path}: the recording has no frames")
        writer = UsdWriter(output, recording.build_model(), recording.frame_interval)
        for k in range(recording.frame_count):
            writer.write(float(recording.time[k]), recording.positions(k))
        return writer.close()


def validate(path) -> tuple[list[str], list[str]]:
    """Run every validator registered with ``pxr.UsdValidation`` on the stage at ``path``.

    Returns ``(names of the validators run, error messages)``; an empty error list means it passed.
    """
    from pxr import UsdValidation

    registry = UsdValidation.ValidationRegistry()
    validators = registry.GetOrLoadAllValidators()
    stage = Usd.Stage.Open(str(path))
    errors = UsdValidation.ValidationContext(validators).Validate(stage)
    return [v.GetMetadata().name for v in validators], [e.GetMessage() for e in errors]
