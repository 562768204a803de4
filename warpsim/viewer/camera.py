"""The viewer's cameras: orbit, chase behind the object, and a ground observer who keeps the horizon and the
objects in the picture. Each is a function of a :class:`~warpsim.viewer.core.Viewer` (its frame, draw list,
orbit and camera mode)."""

from __future__ import annotations

import math

import numpy as np

from .backend import View


def centre(viewer) -> np.ndarray:
    """Centre of the bounding box of the particles the camera frames [m] (``DrawList.focus``)."""
    p = viewer.draw_list.place(viewer.frame.positions)[viewer.draw_list.focus]
    return (p.min(axis=0) + p.max(axis=0)) / 2


def ground_point(viewer) -> np.ndarray:
    """Where the ground observer stands, eyes at 1.7 m: 10 m behind the walked line's anchor (a kite's:
    :class:`~warpsim.objects.keys.WalkKeys`) and 12 m to its side (the line seen from the side), else 20 m behind
    and 30 m to the side of the objects' start."""
    if viewer.walked is not None:
        anchor = np.asarray(viewer._anchor(), dtype=np.float64)
        ahead = viewer._bearing(anchor)
        x, y = anchor - 10.0 * ahead + 12.0 * np.array([-ahead[1], ahead[0]])
    else:
        c = centre(viewer)
        x, y = c[0] - 20.0, c[1] - 30.0
    return np.array([x, y, float(viewer.model.terrain.height(x, y)) + 1.7])


def view(viewer) -> View:
    """The camera of the current mode."""
    target = centre(viewer)
    if viewer.camera == "chase":
        focus = viewer.draw_list.focus
        velocity = viewer.frame.velocities[focus[focus < len(viewer.frame.velocities)]].mean(axis=0)
        if np.linalg.norm(velocity[:2]) > 0.5:
            heading = velocity[:2] / np.linalg.norm(velocity[:2])
            viewer._chase_heading = 0.9 * viewer._chase_heading + 0.1 * heading  # smooth the turns
            viewer._chase_heading /= np.linalg.norm(viewer._chase_heading)
        d = max(viewer.orbit["distance"] * 0.6, 4.0)
        eye = target - d * np.append(viewer._chase_heading, 0.0) + np.array([0.0, 0.0, 0.3 * d])
    elif viewer.camera == "ground":
        if viewer.walked is not None:  # the observer walks with the anchor
            viewer._ground_eye = ground_point(viewer)
        return ground_view(viewer, viewer._ground_eye, target)
    else:
        az, el = np.radians(viewer.orbit["azimuth"]), np.radians(viewer.orbit["elevation"])
        back = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        eye = target + viewer.orbit["distance"] * back
    floor = float(viewer.model.terrain.height(eye[0], eye[1])) + 0.5  # never look from under the ground
    eye = np.array([eye[0], eye[1], max(eye[2], floor)])
    return View(eye=eye, target=target)


def ground_view(viewer, eye: np.ndarray, target: np.ndarray) -> View:
    """The ground observer's view from ``eye`` [m]: turned towards ``target`` and tilted so that the picture
    holds both the horizon (with a strip of ground under it) and the objects, the field of view as narrow as
    that allows (30 to 100 degrees)."""
    p = viewer.points[viewer.draw_list.focus]
    offset = target - eye
    reach = max(float(np.linalg.norm(offset)), 1e-3)
    along = max(float(np.linalg.norm(offset[:2])), 1e-6)
    elevation = math.degrees(math.atan2(offset[2], along))
    size = 0.5 * float(np.linalg.norm(np.ptp(p, axis=0))) if len(p) else 1.0
    half = math.degrees(math.atan2(size, reach))
    low = min(-6.0, elevation - half - 4.0)  # the horizon is at 0
    high = max(elevation + half + 4.0, 0.0)
    fov = min(max(high - low, 30.0), 100.0)
    tilt = math.radians(low + fov / 2 if high - low <= fov else (low + high) / 2)  # horizon low in the picture
    heading = offset[:2] / along
    look = np.append(math.cos(tilt) * heading, math.sin(tilt))
    return View(eye=eye, target=eye + reach * look, fov=fov)
