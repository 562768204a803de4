"""Nails: a nailed particle ignores forces and constraints and sits exactly on its nail's target.

Every kernel that moves particles applies this one rule through :func:`pin_to_nail`; the targets live in
``Control.nail_target`` so that a nail can move while a captured graph replays (the kite's anchor).
"""

from __future__ import annotations

import warp as wp

wp.set_module_options({"enable_backward": False})  # forward-only: halves compile time


@wp.func
def pin_to_nail(
    i: int,
    particle_nail: wp.array(dtype=wp.int32),
    nail_target: wp.array(dtype=wp.vec3d),
    particle_q_out: wp.array(dtype=wp.vec3d),
) -> bool:
    """Put particle ``i`` on its nail's target [m] when it has a nail; returns whether it did."""
    nail = particle_nail[i]
    if nail >= 0:
        particle_q_out[i] = nail_target[nail]
        return True
    return False
