"""Builders of the flying objects. Each adds its particles, sticks, triangles and nails to a
:class:`warpsim.ModelBuilder` with the paper's numbers as defaults and returns an :class:`ObjectRecord`."""
