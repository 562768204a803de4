"""Induced velocities and the lattice's linear system, for the vortex law (:mod:`.vortex`) and the shed wake
(:mod:`.wake`).

* Biot-Savart's law for a straight vortex segment, a semi-infinite ray and a panel's ring, with a cut-off core
  (Katz & Plotkin, *Low-Speed Aerodynamics*, 2nd ed., eqs. 10.115-10.116 and section 11.5); velocities [m/s] per
  unit circulation [m^2/s] at a point [m];
* each surface's influence matrix (one thread per row: the velocity every ring and its wake legs induce at a
  panel's centroid, along its normal), its factorisation by Gaussian elimination with partial pivoting (one thread
  per surface) and the substitution that gives the circulations every step.
"""

from __future__ import annotations

import warp as wp

from .. import lattice

wp.set_module_options({"enable_backward": False})

INV_FOUR_PI = wp.constant(0.07957747154594767)
TRAILING = wp.constant(lattice.TRAILING)


@wp.func
def segment_velocity(x: wp.vec3, a: wp.vec3, b: wp.vec3, core2: float) -> wp.vec3:
    """Velocity [m/s] at ``x`` induced by a straight vortex segment ``a -> b`` [m] of unit circulation [m^2/s]
    (Biot-Savart, Katz & Plotkin eq. 10.115), with a cut-off core of squared radius ``core2`` [m^2]."""
    r1 = x - a
    r2 = x - b
    r0 = b - a
    c = wp.cross(r1, r2)
    n1 = wp.length(r1)
    n2 = wp.length(r2)
    if n1 == 0.0 or n2 == 0.0:
        return wp.vec3(0.0)
    den = wp.dot(c, c) + core2 * wp.dot(r0, r0)
    if den == 0.0:
        return wp.vec3(0.0)
    return c * (INV_FOUR_PI * wp.dot(r0, r1 / n1 - r2 / n2) / den)


@wp.func
def ray_velocity(x: wp.vec3, a: wp.vec3, d: wp.vec3, core2: float) -> wp.vec3:
    """Velocity [m/s] at ``x`` induced by a semi-infinite vortex line of unit circulation leaving ``a`` [m] along the
    unit direction ``d`` (the segment's law as its far end goes to infinity), cut-off core ``core2`` [m^2]."""
    r1 = x - a
    n1 = wp.length(r1)
    if n1 == 0.0:
        return wp.vec3(0.0)
    c = wp.cross(d, r1)
    den = wp.dot(c, c) + core2
    if den == 0.0:
        return wp.vec3(0.0)
    return c * (INV_FOUR_PI * (1.0 + wp.dot(d, r1) / n1) / den)


@wp.func
def ring_velocity(
    x: wp.vec3, panel: int, corners: wp.array(dtype=wp.vec3), trailing: int, d: wp.vec3, core2: float
) -> wp.vec3:
    """Velocity [m/s] at ``x`` from ``panel``'s ring of unit circulation and, at its trailing edges (bits of
    ``trailing``), the wake legs along ``d`` that replace them."""
    v = wp.vec3(0.0)
    for e in range(3):
        a = corners[3 * panel + e]
        b = corners[3 * panel + (e + 1) % 3]
        if ((trailing >> e) & 1) != 0:
            v += ray_velocity(x, a, d, core2) - ray_velocity(x, b, d, core2)
        else:
            v += segment_velocity(x, a, b, core2)
    return v


@wp.kernel
def matrix_rows(
    panel_surface: wp.array(dtype=wp.int32),
    panel_trailing: wp.array(dtype=wp.int32),
    surface_start: wp.array(dtype=wp.int32),
    matrix_start: wp.array(dtype=wp.int64),
    counter: wp.array(dtype=wp.int32),
    factored: wp.array(dtype=wp.int32),
    corners: wp.array(dtype=wp.vec3),
    point: wp.array(dtype=wp.vec3),
    normal: wp.array(dtype=wp.vec4),
    wake: wp.array(dtype=wp.vec4),
    matrix_out: wp.array(dtype=wp.float32),
):
    i = wp.tid()  # one row: the normal velocity at centroid i of every ring of its surface
    s = panel_surface[i]
    if counter[0] != 0 and factored[s] != 0:  # rebuilt on schedule, or at once while the last try failed
        return
    first = surface_start[s]
    count = surface_start[s + 1] - first
    wk = wake[s]
    d = wp.vec3(wk[0], wk[1], wk[2])
    nv = normal[i]
    n = wp.vec3(nv[0], nv[1], nv[2])
    x = point[i]
    row = matrix_start[s] + wp.int64((i - first) * count)
    j = int(0)  # noqa: UP018
    while j < count:
        v = ring_velocity(x, first + j, corners, panel_trailing[first + j], d, wk[3])
        matrix_out[row + wp.int64(j)] = wp.dot(v, n)
        j += 1


@wp.kernel
def factor_lu(
    surface_start: wp.array(dtype=wp.int32),
    matrix_start: wp.array(dtype=wp.int64),
    counter: wp.array(dtype=wp.int32),
    wake: wp.array(dtype=wp.vec4),
    matrix_out: wp.array(dtype=wp.float32),
    pivot_out: wp.array(dtype=wp.int32),
    factored_out: wp.array(dtype=wp.int32),
):
    s = wp.tid()  # LU factors of one surface's matrix, in place (Gaussian elimination, partial pivoting)
    if counter[0] != 0 and factored_out[s] != 0:
        return
    first = surface_start[s]
    n = surface_start[s + 1] - first
    base = matrix_start[s]
    ok = int(1)  # noqa: UP018 -- Warp needs int() for a variable a loop changes
    if wake[s][3] == 0.0:  # no relative wind, no wake direction: no circulation (tried again next step)
        ok = 0
    scale = float(0.0)  # noqa: UP018
    for e in range(n * n):
        scale = wp.max(scale, wp.abs(matrix_out[base + wp.int64(e)]))
    tiny = 1.0e-6 * scale  # a pivot below this is singular in float32: no circulation rather than a huge one
    k = int(0)  # noqa: UP018
    while k < n and ok == 1:
        p = int(k)
        big = float(wp.abs(matrix_out[base + wp.int64(k * n + k)]))
        r = int(k + 1)
        while r < n:
            value = wp.abs(matrix_out[base + wp.int64(r * n + k)])
            if value > big:
                big = value
                p = r
            r += 1
        pivot_out[first + k] = p
        if not (big > tiny):  # also catches NaN
            ok = 0
        else:
            if p != k:
                c = int(0)  # noqa: UP018
                while c < n:
                    t = matrix_out[base + wp.int64(k * n + c)]
                    matrix_out[base + wp.int64(k * n + c)] = matrix_out[base + wp.int64(p * n + c)]
                    matrix_out[base + wp.int64(p * n + c)] = t
                    c += 1
            inv = 1.0 / matrix_out[base + wp.int64(k * n + k)]
            r = int(k + 1)
            while r < n:
                f = matrix_out[base + wp.int64(r * n + k)] * inv
                matrix_out[base + wp.int64(r * n + k)] = f  # L below the diagonal
                if f != 0.0:
                    c = int(k + 1)
                    upper = base + wp.int64(k * n)
                    lower = base + wp.int64(r * n)
                    while c < n:
                        matrix_out[lower + wp.int64(c)] = (
                            matrix_out[lower + wp.int64(c)] - f * matrix_out[upper + wp.int64(c)]
                        )
                        c += 1
                r += 1
        k += 1
    factored_out[s] = ok


@wp.kernel
def substitute(
    surface_start: wp.array(dtype=wp.int32),
    matrix_start: wp.array(dtype=wp.int64),
    normal: wp.array(dtype=wp.vec4),
    panel_wind: wp.array(dtype=wp.vec3),
    matrix: wp.array(dtype=wp.float32),
    pivot: wp.array(dtype=wp.int32),
    factored: wp.array(dtype=wp.int32),
    wake_normal: wp.array(dtype=wp.float32),
    gamma_out: wp.array(dtype=wp.float32),
):
    s = wp.tid()  # this step's circulations from the latest factors: no air through any centroid
    first = surface_start[s]
    n = surface_start[s + 1] - first
    base = matrix_start[s]
    for i in range(n):
        nv = normal[first + i]
        gamma_out[first + i] = -wp.dot(panel_wind[first + i], wp.vec3(nv[0], nv[1], nv[2])) - wake_normal[first + i]
    if factored[s] == 0:
        for i in range(n):
            gamma_out[first + i] = 0.0
        return
    for k in range(n):  # the rows' swaps, in order
        p = pivot[first + k]
        if p != k:
            t = gamma_out[first + k]
            gamma_out[first + k] = gamma_out[first + p]
            gamma_out[first + p] = t
    r = int(1)  # noqa: UP018
    while r < n:  # forward: L has ones on its diagonal
        acc = float(gamma_out[first + r])
        row = base + wp.int64(r * n)
        c = int(0)  # noqa: UP018
        while c < r:
            acc -= matrix[row + wp.int64(c)] * gamma_out[first + c]
            c += 1
        gamma_out[first + r] = acc
        r += 1
    r = n - 1  # noqa: PLW2901
    while r >= 0:  # backward
        acc = float(gamma_out[first + r])
        row = base + wp.int64(r * n)
        c = int(r + 1)
        while c < n:
            acc -= matrix[row + wp.int64(c)] * gamma_out[first + c]
            c += 1
        gamma_out[first + r] = acc / matrix[row + wp.int64(r)]
        r -= 1


@wp.kernel
def tick(interval: int, counter_out: wp.array(dtype=wp.int32)):
    counter_out[0] = (counter_out[0] + 1) % interval


@wp.func
def wake_velocity(
    x: wp.vec3,
    first: int,
    end: int,
    panel_trailing: wp.array(dtype=wp.int32),
    corners: wp.array(dtype=wp.vec3),
    gamma: wp.array(dtype=wp.float32),
    d: wp.vec3,
    core2: float,
) -> wp.vec3:
    """Velocity [m/s] at ``x`` induced by the wake legs of panels ``first .. end - 1`` (their circulations)."""
    v = wp.vec3(0.0)
    j = first
    while j < end:
        bits = panel_trailing[j]
        if bits != 0:
            for e in range(3):
                if ((bits >> e) & 1) != 0:
                    a = corners[3 * j + e]
                    b = corners[3 * j + (e + 1) % 3]
                    v += (ray_velocity(x, a, d, core2) - ray_velocity(x, b, d, core2)) * gamma[j]
        j += 1
    return v
