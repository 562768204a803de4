"""The hang glider in flight: what its controls set (the pilot's arms and the billow shift's struts, from
``pitch`` and ``roll`` in [-1, 1]) and what is read off it (bank, pitch, airspeed, the pilot's offset), all from
its :class:`~warpsim.objects.hang_glider.HangGliderRecord` (``record`` below; typed as its base here, since
:mod:`warpsim.objects.hang_glider` imports this module) and the particles' positions [m]."""

from __future__ import annotations

import numpy as np

from ..physics.model import Model, ObjectRecord
from .figures import FigureView, Measure


def control_rest_lengths(record: ObjectRecord, pitch: float, roll: float) -> np.ndarray:
    """Rest lengths [m] of the control sticks for ``pitch`` and ``roll`` in [-1, 1].

    The pilot's target sits ``pitch * pitch_travel`` forward and ``roll * roll_travel`` to the right of
    the neutral point (glider frame at build time); each control stick's rest length is the distance
    from that target to its frame point. On a hang strap the target is then put back on the strap's sphere
    around the hang point (the pilot swings; the strap does not stretch).
    """
    for name, value in (("pitch", pitch), ("roll", roll)):
        if not -1.0 <= value <= 1.0:
            raise ValueError(f"{name} must be in [-1, 1], got {value}")
    target = record.pilot_neutral_frame + np.array([pitch * record.pitch_travel, -roll * record.roll_travel, 0.0])
    if record.hang_point_frame is not None:
        strap = np.linalg.norm(record.pilot_neutral_frame - record.hang_point_frame)
        d = target - record.hang_point_frame
        target = record.hang_point_frame + d * (strap / np.linalg.norm(d))
    return np.linalg.norm(record.pilot_attach_frame - target, axis=1)


def apply_controls(record: ObjectRecord, targets: dict, values: dict) -> None:
    """Write the control sticks' rest lengths for ``values['pitch']``/``values['roll']`` (every control in
    force; one never set is 0) into ``targets['stick_rest']`` (a host copy of ``Control.stick_rest``)."""
    pitch, roll = float(values.get("pitch", 0.0)), float(values.get("roll", 0.0))
    targets["stick_rest"][record.control_sticks] = control_rest_lengths(record, pitch, roll)
    if record.billow_shift != 0.0 and record.billow_sticks is not None:
        targets["stick_rest"][record.billow_sticks] = billow_rest_lengths(record, roll)


def billow_rest_lengths(record: ObjectRecord, roll: float, washout: float = 0.0) -> np.ndarray:
    """Rest lengths [m] of the washout struts' ties at ``roll`` in [-1, 1] (billow shift): the strutted trailing edge
    of the half the pilot moves towards (``roll > 0``: the right) raised as if its washout at the tip were
    ``billow_shift * |roll|`` degrees more, the other half's lowered as much (to first order in the angle); both
    raised by a further ``washout`` degrees at the tip (0 in the model; an experiment's imposed twist)."""
    extra = np.radians(record.billow_shift) * roll * -record.billow_side + np.radians(washout)
    target = record.billow_points + np.outer(record.billow_rise * extra, (0.0, 0.0, 1.0))
    return np.linalg.norm(target - record.billow_anchors, axis=1)


def bank(record: ObjectRecord, q: np.ndarray) -> float:
    """Bank of the sail [deg]: the tip-to-tip line against the horizontal, positive with the right tip lower."""
    span_dir = q[record.tips[0]] - q[record.tips[1]]
    return float(np.degrees(np.arctan2(span_dir[2], np.linalg.norm(span_dir[:2]))))


def flight_state(record: ObjectRecord, q: np.ndarray, q_prev: np.ndarray, dt: float, wind) -> dict:
    """Diagnostics: nose pitch angle [deg], bank [deg], airspeed [m/s], pilot offset [m] in the sail frame."""
    nose = q[record.nose]
    keel_end = q[record.keel[-1]]
    tip_l, tip_r = q[record.tips[0]], q[record.tips[1]]
    keel_dir = nose - keel_end
    pitch = np.degrees(np.arctan2(keel_dir[2], np.linalg.norm(keel_dir[:2])))
    span_dir = tip_l - tip_r
    sail = record.parts["sail"]
    velocity = (q[sail] - q_prev[sail]).mean(axis=0) / dt
    airspeed = float(np.linalg.norm(velocity - np.asarray(wind)))
    fwd = keel_dir / np.linalg.norm(keel_dir)
    left = span_dir / np.linalg.norm(span_dir)
    up = np.cross(fwd, left)
    up /= np.linalg.norm(up)
    pilot = q[record.pilot] - q[sail].mean(axis=0)
    return {
        "pitch_deg": float(pitch),
        "bank_deg": bank(record, q),
        "airspeed": airspeed,
        "velocity": velocity,
        "pilot_forward": float(pilot @ fwd),
        "pilot_left": float(pilot @ left),
        "pilot_up": float(pilot @ up),
        "altitude": float(q[sail][:, 2].mean()),
    }


# ---------------------------------------------------------------------------------------------- figures
GLIDER_FIGURES = {
    "glide": (
        "-",
        "glide ratio: horizontal airspeed / sink of the mass centre (NaN unless it sinks faster than 0.05 m/s)",
    ),
    "bank": ("deg", "bank of the sail, tip to tip against the horizontal, + = right tip lower"),
}


def glider_figures(model: Model, record: ObjectRecord) -> Measure:
    """The hang glider's :data:`GLIDER_FIGURES` of a frame."""

    def measure(view: FigureView) -> dict[str, float]:
        sink = float(-view.velocity[2])
        horizontal = float(np.linalg.norm((view.velocity - view.wind)[:2]))
        return {"glide": horizontal / sink if sink > 0.05 else float("nan"), "bank": bank(record, view.positions)}

    return measure


def glider_hud(f: dict[str, float]) -> str:
    """The hang glider's heads-up text: sink rate, glide ratio and bank with its side."""
    glide = f"{f['glide']:4.1f}" if np.isfinite(f["glide"]) else " -- "
    side = "right" if f["bank"] > 0.5 else "left" if f["bank"] < -0.5 else ""
    return f"sink {f['sink']:5.2f} m/s  glide {glide}  bank {abs(f['bank']):3.0f} deg {side}"
