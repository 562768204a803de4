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


@wp.kernel
def _advance_gusts(
    mean: wp.array(dtype=wp.vec3),
    intensity: wp.array(dtype=wp.float32),
    period: wp.array(dtype=wp.float32),
    seed: wp.array(dtype=wp.int32),
    dt: float,
    g_out: wp.array(dtype=wp.vec3d),
    step_out: wp.array(dtype=wp.int32),
    wind_out: wp.array(dtype=wp.vec3),
):
    w = wp.tid()
    strength = intensity[w]
    if strength <= 0.0:
        return
    decay = wp.exp(-dt / period[w])
    step = step_out[w]
    rng = wp.rand_init(seed[w], step)  # counter-based: the same seed and step count draw the same numbers
    noise = wp.vec3d(wp.float64(wp.randn(rng)), wp.float64(wp.randn(rng)), wp.float64(wp.randn(rng)))
    g = g_out[w] * wp.float64(decay) + noise * wp.float64(wp.sqrt(1.0 - decay * decay))
    g_out[w] = g
    step_out[w] = (step + 1) % 2147483647
    m = mean[w]
    gust = wp.vec3(g) * (strength * wp.length(m))
    wind_out[w] = m + wp.vec3(gust[0], gust[1], 0.5 * gust[2])


def advance_gusts(model, control, dt: float) -> None:
    """Advance every gusty world's gust process by one step of ``dt`` [s] and write its wind into ``control.wind``
    (``mean + intensity * |mean| * (g_x, g_y, g_z / 2)``, ``g`` an Ornstein-Uhlenbeck process of unit variance and
    correlation time ``period``, drawn from counter-based random numbers of the world's seed and its gust step
    count); worlds without gusts keep their wind. Nothing is launched when ``control.gusts`` is None."""
    gusts = control.gusts
    if gusts is None:
        return
    wp.launch(
        _advance_gusts,
        gusts.g.shape[0],
        [gusts.mean, gusts.intensity, gusts.period, gusts.seed, float(dt)],
        [gusts.g, gusts.step, control.wind],
        device=model.device,
    )
