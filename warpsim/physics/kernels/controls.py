"""The inputs a step moves before its forces: the control sticks' rest lengths and the controlled nails' targets move
toward what the controls ask by at most a rate per step (``solver.control_rate`` [m/s], ``solver.nail_rate`` [m/s]),
so that a pilot's weight shift or a walked kite anchor moves as a person does, not in one step; every world's gusts
advance by the step; every world's air density is taken from the standard atmosphere at its altitude."""

from __future__ import annotations

import warp as wp

from .. import atmosphere

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


_T0 = wp.constant(atmosphere.SEA_LEVEL_TEMPERATURE)
_P0 = wp.constant(atmosphere.SEA_LEVEL_PRESSURE)
_R = wp.constant(atmosphere.GAS_CONSTANT)
_LAPSE = wp.constant(atmosphere.LAPSE_RATE)
_H11 = wp.constant(atmosphere.TROPOPAUSE)
_LOW = wp.constant(atmosphere.LOWEST)
_HIGH = wp.constant(atmosphere.HIGHEST)
_G = wp.constant(atmosphere.GRAVITY)
_EARTH = wp.constant(atmosphere.EARTH_RADIUS)


@wp.func
def isa_density(altitude: float, temperature_offset: float) -> float:
    """Density [kg/m^3] of the standard atmosphere at ``altitude`` [m above sea level, geometric, clamped to -2 km to
    20 km] on a day ``temperature_offset`` [K] off the standard (:func:`warpsim.physics.atmosphere.isa`)."""
    z = wp.clamp(altitude, _LOW, _HIGH)
    h = _EARTH * z / (_EARTH + z)  # geopotential
    exponent = _G / (_R * _LAPSE)
    t11 = _T0 - _LAPSE * _H11
    p = float(0.0)  # noqa: UP018
    t = float(0.0)  # noqa: UP018
    if h < _H11:
        t = _T0 - _LAPSE * h
        p = _P0 * wp.pow(t / _T0, exponent)
    else:
        t = t11
        p = _P0 * wp.pow(t11 / _T0, exponent) * wp.exp(-_G * (h - _H11) / (_R * t11))
    return p / (_R * (t + temperature_offset))


@wp.kernel
def _air_density(
    world_start: wp.array(dtype=wp.int32),
    particle_q: wp.array(dtype=wp.vec3d),
    fixed: float,
    elevation: float,
    temperature_offset: float,
    density_out: wp.array(dtype=wp.float32),
):
    w = wp.tid()
    if fixed > 0.0:
        density_out[w] = fixed
        return
    first = world_start[w]
    count = world_start[w + 1] - first
    stride = wp.max(count / 64, 1)  # at most about 64 particles' heights
    total = wp.float64(0.0)
    taken = int(0)  # noqa: UP018
    k = first
    while k < first + count:
        total += particle_q[k][2]
        taken += 1
        k += stride
    z = float(0.0)  # noqa: UP018
    if taken > 0:
        z = float(total / wp.float64(taken))
    density_out[w] = isa_density(z + elevation, temperature_offset)


def update_air_density(model, state, air, world_start: wp.array, density_out: wp.array) -> None:
    """Write each world's air density [kg/m^3] into ``density_out`` (``[W]``): ``air.density`` where the scene fixes
    it, else the standard atmosphere's at the mean altitude of the world's particles (``world_start``, ``[W + 1]``,
    where each world's particles start), ``air.elevation`` [m] above sea level at z = 0, on a day
    ``air.temperature_offset`` [K] off the standard (:mod:`warpsim.physics.atmosphere`)."""
    wp.launch(
        _air_density,
        density_out.shape[0],
        [world_start, state.particle_q, float(air.density), float(air.elevation), float(air.temperature_offset)],
        [density_out],
        device=model.device,
    )


@wp.kernel
def _advance_turbulence(
    wind: wp.array(dtype=wp.vec3),
    intensity: wp.array(dtype=wp.float32),
    dt: float,
    shift_out: wp.array(dtype=wp.vec3d),
    scale_out: wp.array(dtype=wp.float32),
):
    w = wp.tid()
    strength = intensity[w]
    if strength <= 0.0:
        return
    u = wind[w]
    shift_out[w] = shift_out[w] - wp.vec3d(u) * wp.float64(dt)
    scale_out[w] = strength * wp.length(u)


def advance_turbulence(model, control, dt: float) -> None:
    """Carry every turbulent world's frozen field along by its wind at the reference height for one step of ``dt``
    [s] (Taylor's hypothesis) and set its turbulence's standard deviation to ``intensity * |wind|`` [m/s]; nothing is
    launched when no world has turbulence."""
    turbulence = control.turbulence
    if turbulence.field is None:
        return
    wp.launch(
        _advance_turbulence,
        turbulence.intensity.shape[0],
        [control.wind, turbulence.intensity, float(dt)],
        [turbulence.data.shift, turbulence.data.scale],
        device=model.device,
    )
