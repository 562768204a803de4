"""The figures of a frame (what a pilot or an observer reads off each object: altitude, airspeed, sink and each
object's own, named by its ``ObjectSpec``), their window means over a run (a sweep's metrics, ``warpsim run``'s
closing figures) and the lines that print them."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..objects import registry
from ..objects.figures import FigureView
from ..physics.model import Model
from .diagnostics import Frame, GroundContacts, object_metrics

COMMON_FIGURES = {
    "altitude": ("m", "height of the object's mass centre above the terrain under it"),
    "airspeed": ("m/s", "speed of the mass centre relative to its world's wind"),
    "sink": ("m/s", "descent speed of the mass centre (positive downwards)"),
}
"""The figures every object has: name -> (unit, meaning)."""


def _figure_table() -> dict[str, tuple[str, tuple[str, ...] | None, str]]:
    table: dict[str, tuple[str, tuple[str, ...] | None, str]] = {
        name: (unit, None, meaning) for name, (unit, meaning) in COMMON_FIGURES.items()
    }
    for kind, spec in registry.OBJECTS.items():
        for name, (unit, meaning) in spec.figures.items():
            kinds = table[name][1] + (kind,) if name in table else (kind,)
            table[name] = (unit, kinds, meaning)
    return table


FIGURES = _figure_table()
"""The figures :class:`Figures` gives: name -> (unit, the object kinds that have it (None: all), meaning); the
objects' own come from their ``ObjectSpec`` (:mod:`warpsim.objects.registry`)."""


def figure_names(kind: str) -> tuple[str, ...]:
    """The :data:`FIGURES` an object of ``kind`` has, in table order."""
    return tuple(name for name, (_, kinds, _) in FIGURES.items() if kinds is None or kind in kinds)


def oscillations_of(kind: str) -> dict[str, float]:
    """The figures of an object of ``kind`` whose window frequency is measured, with the least half-range (in the
    figure's unit) that counts as a swing (``ObjectSpec.oscillations``)."""
    return dict(registry.OBJECTS[kind].oscillations)


class Figures:
    """What a pilot or an observer reads off each object of a frame (:data:`FIGURES`). The heads-up display and
    the sweeps read their figures here, so each is computed one way; each object's own figures are measured by
    its kind's ``ObjectSpec.measure_figures``, made once per object here.

    Call it with a frame and the solver's ``tri_force`` (device or host ``[T, 3]`` air force per triangle
    vertex [N], copied to the host only when an object's figures need it, as a kite's ``line_pull``; NaN without
    it): one dict per object, in model order, of the figures its kind has, as floats in their units.
    """

    def __init__(self, model: Model):
        self.model = model
        specs = [registry.OBJECTS[record.kind] for record in model.objects]
        self._measures = [
            spec.measure_figures(model, record) if spec.measure_figures is not None else None
            for spec, record in zip(specs, model.objects, strict=True)
        ]
        self._air_force = any(spec.figures_need_air_force for spec in specs)

    def __call__(self, frame: Frame, tri_force=None) -> list[dict[str, float]]:
        if self._air_force and tri_force is not None and not isinstance(tri_force, np.ndarray):
            tri_force = tri_force.numpy()
        metrics = object_metrics(self.model, frame)
        out = []
        for k, record in enumerate(self.model.objects):
            v = metrics.velocity[k]
            values = {
                "altitude": float(metrics.altitude[k]),
                "airspeed": float(metrics.airspeed[k]),
                "sink": float(-v[2]),
            }
            measure = self._measures[k]
            if measure is not None:
                values.update(measure(FigureView(frame.positions, v, frame.wind[record.world], tri_force)))
            out.append(values)
        return out


class FigureWindow:
    """Window means, minima and maxima of each world's figures (:data:`FIGURES`, in their units), the share of
    frames airborne, the first ground contact [s] and the worst stretch, for ``count`` worlds (float64, frame
    order: the same sums for a case whatever chunk it runs in). A sweep's metrics and ``warpsim run``'s closing
    figures are both these.

    For the figures named in ``oscillating`` (name -> least half-range that counts as a swing: a flag's flap,
    1 cm) it keeps each world's window series (a float32 ``[frames, count]`` buffer, 4 bytes per world and frame,
    grown by doubling) and gives ``NAME_frequency`` [Hz] by :func:`swing_frequency`, the peak of the series'
    spectrum for a flag that flaps steadily.
    """

    def __init__(self, count: int, figures: Sequence[str], oscillating: dict[str, float] | None = None):
        self.figures = list(figures)
        oscillating = dict(oscillating or {})
        self.oscillating = [self.figures.index(name) for name in oscillating]
        self.least = [float(least) for least in oscillating.values()]
        self.series = np.zeros((len(self.oscillating), 64 if self.oscillating else 0, count), dtype=np.float32)
        self.series_times = np.zeros(self.series.shape[1])
        self.series_count = 0
        self.sum = np.zeros((len(figures), count))
        self.n = np.zeros((len(figures), count))
        self.low = np.full((len(figures), count), np.inf)
        self.high = np.full((len(figures), count), -np.inf)
        self.frames = np.zeros(count, dtype=np.int64)
        self.airborne = np.zeros(count, dtype=np.int64)
        self.ground_time = np.full(count, np.nan)
        self.worst = np.zeros(count)

    def add(self, values: np.ndarray, live: np.ndarray, in_window: bool, touching: np.ndarray, t: float) -> None:
        """Add one frame: ``values`` ``[F, count]`` figures, for the ``live`` worlds (not read outside the window)."""
        first = live & touching & np.isnan(self.ground_time)
        self.ground_time[first] = t
        if not in_window:
            return
        self.frames[live] += 1
        self.airborne[live & ~touching] += 1
        ok = np.isfinite(values) & live[None, :]
        self.sum += np.where(ok, values, 0.0)
        self.n += ok
        self.low = np.where(ok, np.minimum(self.low, values), self.low)
        self.high = np.where(ok, np.maximum(self.high, values), self.high)
        if self.oscillating:
            if self.series_count == self.series.shape[1]:  # full: twice the room
                self.series = np.concatenate([self.series, np.zeros_like(self.series)], axis=1)
                self.series_times = np.concatenate([self.series_times, np.zeros_like(self.series_times)])
            for k, f in enumerate(self.oscillating):
                self.series[k, self.series_count] = np.where(ok[f], values[f], np.nan)
            self.series_times[self.series_count] = t
            self.series_count += 1

    def row(self, k: int) -> dict:
        """The metrics of world ``k``."""
        out: dict = {}
        for f, name in enumerate(self.figures):
            n = self.n[f, k]
            out[f"{name}_mean"] = self.sum[f, k] / n if n else math.nan
            out[f"{name}_min"] = self.low[f, k] if n else math.nan
            out[f"{name}_max"] = self.high[f, k] if n else math.nan
        n = self.series_count
        for j, f in enumerate(self.oscillating):
            series = self.series[j, :n, k].astype(np.float64)
            out[f"{self.figures[f]}_frequency"] = swing_frequency(self.series_times[:n], series, least=self.least[j])
        frames = int(self.frames[k])
        out["airborne"] = self.airborne[k] / frames if frames else math.nan
        out["ground_time"] = float(self.ground_time[k])
        out["worst_stretch"] = 100.0 * float(self.worst[k])  # in percent, as the run summary prints it
        out["window_frames"] = frames
        return {key: float(v) if isinstance(v, np.floating) else v for key, v in out.items()}


class FlightFigures:
    """A run's closing figures: each world's :data:`FIGURES` over the window ``[start, stop]`` [s] of simulated
    time, from the frames a run hands out (call it with each :class:`Frame`), every frame as a sweep measures it
    (:class:`FigureWindow`), or at most ``rate`` frames per simulated second.

    Args:
        sim: the :class:`~warpsim.run.simulation.Simulation` (its model, object kind, frame interval and air forces).
        start, stop: the window [s].
        rate: frames measured per simulated second, at most [1/s] (None: every frame, as a sweep).
    """

    def __init__(self, sim, start: float, stop: float, rate: float | None = None):
        self.sim, self.start, self.stop = sim, float(start), float(stop)
        self.kind = sim.scene.kind
        self.names = list(figure_names(self.kind))
        interval = sim.steps_per_frame * sim.dt
        self.every = 1 if rate is None else max(1, int(round(1.0 / (rate * interval))))
        self.oscillating = oscillations_of(self.kind)
        self.window = FigureWindow(sim.model.world_count, self.names, self.oscillating)
        self.measure = Figures(sim.model)
        self.contacts = GroundContacts(sim.model)
        self.live = np.ones(sim.model.world_count, dtype=bool)
        self._seen = 0

    def __call__(self, frame: Frame) -> None:
        # every frame, as a sweep: each world's worst stretch as the device measured it, and its first ground contact
        self.window.worst = np.maximum(self.window.worst, frame.world_stretch)
        eps = 0.25 * self.sim.dt  # frame times are sums of dt
        if not self.start - eps <= frame.time <= self.stop + eps:
            self.window.add(None, self.live, False, self.contacts.touching(frame), frame.time)
            return
        self._seen += 1
        if (self._seen - 1) % self.every:
            return
        found = self.measure(frame, self.sim.solver.tri_force)
        values = np.array([[f[name] for f in found] for name in self.names], dtype=np.float64)
        self.window.add(values, self.live, True, self.contacts.touching(frame), frame.time)

    def rows(self) -> list[dict]:
        """One dict per world, after the run: ``world``, ``object``, the settings varied between the worlds
        (``wind.speed``...), the window and the sweep's columns (``altitude_mean``, ``line_angle_mean``,
        ``worst_stretch``...: :data:`FIGURES`' names with ``_mean``, ``_min``, ``_max`` and the oscillations'
        ``_frequency``, in their units); what ``warpsim run --table`` writes."""
        varied = self.sim.scene.varied
        objects = {record.world: record.name for record in self.sim.model.objects}
        rows = []
        for k in range(self.window.frames.size):
            row = {"world": k, "object": objects.get(k, "")}
            row.update({key: values[k] for key, values in varied.items()})
            row.update({"window_start": self.start, "window_stop": self.stop})
            row.update(self.window.row(k))
            rows.append(row)
        return rows

    def lines(self) -> list[str]:
        """The figures as summary lines: per object with one world; over the worlds (mean, lowest, highest of the
        worlds' window means) with several. Empty when no frame fell in the window."""
        frames = int(self.window.frames.max()) if self.window.frames.size else 0
        if frames == 0:
            return []
        count = self.window.frames.size
        rows = [self.window.row(k) for k in range(count)]

        def shown(values: list[float], unit: str) -> str | None:
            """The worlds' mean of ``values`` (and their range with several worlds), in ``unit``; None if none."""
            values = [v for v in values if np.isfinite(v)]
            if not values:
                return None
            text = f"{_figure(np.mean(values))}{'' if unit == '-' else ' ' + unit}"
            return text + (f" ({_figure(min(values))} to {_figure(max(values))})" if count > 1 else "")

        def part(name: str) -> str | None:
            """A figure's window mean, or for an oscillating one its half-range (amplitude) and frequency."""
            label, unit = name.replace("_", " "), FIGURES[name][0]
            if name not in self.oscillating:
                mean = shown([r[f"{name}_mean"] for r in rows], unit)
                return None if mean is None else f"{label} {mean}"
            amplitude = shown([0.5 * (r[f"{name}_max"] - r[f"{name}_min"]) for r in rows], unit)
            frequency = shown([r[f"{name}_frequency"] for r in rows], "Hz")
            if amplitude is None:
                return None
            return f"{label} \u00b1{amplitude}" + (f" at {frequency}" if frequency is not None else "")

        parts = [part(name) for name in self.names]
        parts = [p for p in parts if p is not None]
        where = f"means over {self.start:g}-{self.stop:g} s, {frames} frames"
        if count == 1:
            head = f"  {self.sim.model.objects[0].name}"
        else:
            head = f"  {count} worlds (mean, lowest to highest world)"
        caveat = registry.OBJECTS[self.kind].caveat
        notes: list[str] = []
        if caveat is not None:  # each world's own, once (a sweep of --vary may give its worlds different cloth)
            for k in range(count):
                world = self.sim.scene.world(k)
                note = caveat(world.object_config(), world.settings)
                if note and note not in notes:
                    notes.append(note)
        some = "some worlds: " if count > 1 and len(notes) > 1 else ""
        return [f"{head}: {', '.join(parts)} ({where})"] + [f"  {some}{note}" for note in notes] + self._air_lines()

    def _air_lines(self) -> list[str]:
        """What the figures depend on beyond the object's shape: the air's density (the standard atmosphere's at the
        end, or the fixed one), the turbulence."""
        air, wind, lines = self.sim.settings.air, self.sim.settings.wind, []
        if air.density == 0.0:
            rho = self.sim.control.air_density.numpy()
            text = f"{rho.mean():.4g} kg/m^3" if len(rho) == 1 else f"{rho.min():.4g} to {rho.max():.4g} kg/m^3"
            if not np.isfinite(rho).all():
                text = "not known at the end (the run blew up)"
            lines.append(
                f"  air: the standard atmosphere, {text} at the end ({air.elevation:g} m above sea level at z = 0, "
                f"ISA{air.temperature_offset:+g} K)"
            )
        elif air.scale > 0.0:
            lines.append(f"  air: a fixed density, {air.density:.6g} kg/m^3 (air.density; 0 = the standard atmosphere)")
        if self.sim.control.turbulence.field is not None:
            lines.append(
                f"  turbulence: von Karman, intensity {wind.turbulence_intensity:g}, length scale "
                f"{wind.turbulence_length:g} m"
            )
        return lines


def swing_frequency(times: np.ndarray, values: np.ndarray, hysteresis: float = 0.25, least: float = 0.0) -> float:
    """Frequency [Hz] of the swings of ``values`` (at ``times`` [s]) through their median: a crossing counts when
    the values go from more than ``hysteresis`` of their half-range above the median to as far below, or back;
    half the crossings after the first over the time from the first to the last. The half-range is that of the
    5th to 95th percentiles, so that a spike or a settling start does not set it. NaN before three crossings, with
    no finite value, or when the half-range is under ``least`` (in the values' unit: a figure that does not swing,
    whose jitter is not counted)."""
    ok = np.isfinite(values)
    times, values = times[ok], values[ok]
    if len(values) < 3:
        return math.nan
    low, centre, high = np.percentile(values, [5.0, 50.0, 95.0])
    half = 0.5 * float(high - low)
    if not half > least:
        return math.nan
    band = hysteresis * half
    side = np.where(values > centre + band, 1, np.where(values < centre - band, -1, 0))
    out = side != 0
    side, times = side[out], times[out]
    flips = np.nonzero(np.diff(side))[0] + 1  # where each crossing lands
    if len(flips) < 3 or times[flips[-1]] <= times[flips[0]]:
        return math.nan
    return (len(flips) - 1) / (2.0 * float(times[flips[-1]] - times[flips[0]]))


def _figure(value: float) -> str:
    """``value`` to three significant digits, in fixed point with at most two decimals (0.00 for what is smaller)."""
    value = float(value)
    digits = 2 if abs(value) < 1e-2 else min(2, max(0, 2 - math.floor(math.log10(abs(value)))))
    text = f"{value:.{digits}f}"
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


@dataclass(frozen=True)
class Flight:
    """A run and its closing figures (:meth:`warpsim.run.simulation.Simulation.fly`): what ``warpsim run``
    prints, as numbers and as text.

    Attributes:
        summary: the run's :class:`~warpsim.run.summary.RunSummary` (simulated and wall time, steps, worst stretch).
        figures: the :class:`FlightFigures` over the run's second half.
    """

    summary: object
    figures: FlightFigures

    def rows(self) -> list[dict]:
        """Each world's figures (:meth:`FlightFigures.rows`)."""
        return self.figures.rows()

    def lines(self) -> list[str]:
        """The lines ``warpsim run`` prints at the end: the summary, then the figures."""
        return [self.summary.text(), *self.figures.lines()]
