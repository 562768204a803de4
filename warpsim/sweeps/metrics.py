"""What a sweep measures: the metric catalogue (:data:`METRICS`, from each object's figures), the metrics an object
kind has, and the optional imports of the ``[sweep]`` extra."""

from __future__ import annotations

from collections.abc import Sequence

from .._extras import install_hint
from ..run.figures import FIGURES, oscillations_of
from ..scene.values import suggest

EXTRA_HINT = install_hint("sweep")


class SweepError(ValueError):
    """A sweep a user asked for cannot run as given (bad axes, metrics, window or output); one line says why."""


def require(module: str):
    """Import ``module`` of the ``[sweep]`` extra, or raise :class:`SweepError` saying how to install it."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        name = {"distributed": "Dask", "dask": "Dask", "cryptography": "cryptography (TLS for the local cluster)"}.get(
            module.split(".")[0], module
        )
        raise SweepError(f"sweeps need {name}: {EXTRA_HINT}") from None


def _metric_table() -> dict[str, tuple[str, tuple[str, ...] | None, str]]:
    table: dict[str, tuple[str, tuple[str, ...] | None, str]] = {}
    for name, (unit, kinds, meaning) in FIGURES.items():
        for reduce in ("mean", "min", "max"):
            table[f"{name}_{reduce}"] = (unit, kinds, f"{reduce} over the window of the {meaning}")
        if kinds is not None and any(name in oscillations_of(kind) for kind in kinds):
            table[f"{name}_frequency"] = ("Hz", kinds, f"frequency of the swings over the window of the {meaning}")
    table.update(
        {
            "airborne": ("-", None, "share of the window's frames in which the object does not touch the terrain"),
            "ground_time": ("s", None, "first time the object touched the terrain (NaN: never), whole run"),
            "worst_stretch": ("%", None, "largest |l - r|/r of the case's sticks over the whole run, in percent"),
            "window_frames": ("-", None, "frames measured in the window (fewer when the case blew up in it)"),
            "blew_up": ("-", None, "true when the case blew up (or could not be built); always in the table"),
            "blowup_time": ("s", None, "when it blew up (NaN: it did not, or was never built); always in the table"),
            "blowup_reason": ("-", None, "what was seen ('' when it did not blow up); always in the table"),
        }
    )
    return table


METRICS = _metric_table()
"""Every metric a sweep can report: name -> (unit, object kinds that have it (None: all), meaning). The
window is ``--window START:STOP`` [s] of simulated time (default: the second half of the run); a frame is
measured ``scene.fps`` times per simulated second. Means, minima and maxima skip frames where a figure is
undefined (a glide ratio while climbing)."""


ALWAYS = ("blew_up", "blowup_time", "blowup_reason")


def metrics_of(kind: str, names: Sequence[str] | None = None) -> tuple[str, ...]:
    """The metric columns of a sweep of ``kind`` objects: ``names`` checked (any order; the blow-up columns
    are added), or every metric the kind has. Raises :class:`SweepError` for a name it does not have."""
    have = tuple(n for n, (_, kinds, _) in METRICS.items() if kinds is None or kind in kinds)
    if names is None or not len(names):
        return have
    for name in names:
        if name not in have:
            hint = suggest(name, have)
            raise SweepError(f"--metrics: a {kind} has no metric {name!r}{hint}; it has {', '.join(have)}")
    chosen = set(names) | set(ALWAYS)
    return tuple(n for n in have if n in chosen)
