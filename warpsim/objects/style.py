"""How each part is drawn: display colours (RGB, 0-1), sphere radii and curve widths [m]; shared by the USD stage,
the picture renderer and the viewer (which must not load USD to know them)."""

COLOURS = {
    "terrain": (0.42, 0.50, 0.32),
    "sail": (0.15, 0.45, 0.85),
    "cloth": (0.85, 0.20, 0.20),
    "keel": (0.90, 0.35, 0.15),
    "canopy": (0.95, 0.75, 0.20),
    "rope": (0.15, 0.15, 0.15),
    "lines": (0.25, 0.25, 0.25),
    "pilot": (0.95, 0.55, 0.10),
    "person": (0.95, 0.55, 0.10),
}
SPHERE_PARTS = {"pilot": 0.3, "person": 0.3}  # radius [m]
CURVE_WIDTH = {"rope": 0.03, "lines": 0.02}  # [m]
