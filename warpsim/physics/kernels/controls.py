"""Controls that ramp: the control sticks' rest lengths and the controlled nails' targets move toward what the
controls ask by at most a rate per step (``solver.control_rate`` [m/s], ``solver.nail_rate`` [m/s]), so that a
pilot's weight shift or a walked kite anchor moves as a person does, not in one step."""

from __future__ import annotations

import warp as wp

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


@wp.kernel
def _ramp_rest(
    sticks: wp.array(dtype=wp.int32),
    stick_rest_target: wp.array(dtype=wp.float32),
    most: float,
    stick_rest_out: wp.array(dtype=wp.float32),
):
    k = wp.tid()
    s = sticks[k]
    rest = stick_rest_out[s]
    change = stick_rest_target[s] - rest
    if most > 0.0:
        change = wp.clamp(change, -most, most)
    stick_rest_out[s] = rest + change


def ramp_rest_lengths(model, control, sticks: wp.array, most: float) -> None:
    """Move the rest lengths of ``sticks`` (``[K]`` int32 indices, the control sticks) toward
    ``control.stick_rest_target`` by at most ``most`` [m] (0: all the way), in place in ``control.stick_rest``."""
    if control.stick_rest_target is not None and sticks.shape[0]:
        wp.launch(
            _ramp_rest,
            sticks.shape[0],
            [sticks, control.stick_rest_target, float(most)],
            [control.stick_rest],
            device=model.device,
        )


@wp.kernel
def _ramp_nails(
    nails: wp.array(dtype=wp.int32),
    nail_target_goal: wp.array(dtype=wp.vec3d),
    most: wp.float64,
    nail_target_out: wp.array(dtype=wp.vec3d),
):
    k = wp.tid()
    n = nails[k]
    move = nail_target_goal[n] - nail_target_out[n]
    length = wp.length(move)
    if most > wp.float64(0.0) and length > most:
        move = move * (most / length)
    nail_target_out[n] = nail_target_out[n] + move


def ramp_nail_targets(model, control, nails: wp.array, most: float) -> None:
    """Move the targets of ``nails`` (``[K]`` int32 nail indices, the controlled ones) toward
    ``control.nail_target_goal`` by at most ``most`` [m] (0: all the way), in place in ``control.nail_target``."""
    if control.nail_target_goal is not None and nails.shape[0]:
        wp.launch(
            _ramp_nails,
            nails.shape[0],
            [nails, control.nail_target_goal, wp.float64(most)],
            [control.nail_target],
            device=model.device,
        )
