"""The built-in objects: config class (defaults and bounds of its keys), builder, scene defaults and controls.

A new object is added here (see README: adding an object)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from . import flag, glider_flight, hang_glider, kite, mesh, parachute
from .keys import line_walk_keys, weight_shift_keys


@dataclass(frozen=True)
class ObjectSpec:
    """How to build one kind of object from its descriptor section.

    Attributes:
        config: dataclass of the object's parameters (the descriptor section's keys and defaults).
        build: ``build(builder, config, terrain) -> ObjectRecord``.
        scene_defaults: overrides of other sections that suit this object (e.g. its wind, its dt).
        summary: one line for ``warpsim list``.
        controls: names of the object's controls (see :mod:`warpsim.scene.controls`; every scene also has ``wind``).
        apply_controls: ``apply_controls(record, targets, values)`` writes what the controls in force
            (``values``: every control set so far but ``wind``) change into ``targets`` (host copies of
            ``stick_rest`` and ``nail_target``, and the ``terrain``).
        presets: for an object with a ``design`` key, the values each design gives to keys of any section
            (``{design: {section: {key: value}}}``). The default design's preset is part of the defaults;
            setting ``design`` in a scene or with ``--set`` applies its preset first, then the scene's own keys.
        figures: the object's own figures besides those of every object (altitude, airspeed, sink):
            ``{name: (unit, meaning)}``, in the order tables show them (see :mod:`.figures`).
        measure_figures: ``measure_figures(model, record) -> measure``, where ``measure(view)`` gives those
            figures of a frame (a :class:`~.figures.FigureView`) by name; None for an object with none.
        figures_need_air_force: True when ``measure`` reads the view's ``tri_force`` (it is copied to the host
            only then).
        hud: ``hud(figures) -> str``, the object's own part of its heads-up line (after altitude and airspeed),
            from its figures of a frame by name; None for an object with none.
        oscillations: those of its figures that swing about a mean, whose frequency over a window is measured too
            (``NAME_frequency`` [Hz], :class:`warpsim.run.figures.FigureWindow`), each with the least half-range
            (in the figure's unit) that counts as a swing.
        caveat: ``caveat(config, settings) -> str | None`` (the object's config and the scene's typed settings,
            :class:`~warpsim.scene.build.Settings`, of one world): what the run's closing figures are not, said
            under them (e.g. a figure set by the mesh rather than by the object's physics); None when there is
            nothing to say.
        paper_counts: the paper's particle, stick and triangle counts of this object, where it gives them
            (``warpsim info`` prints them beside the model's).
        wind_limit: the strongest wind [m/s] the object is made to fly in: the viewer's + key stops there (or at
            the scene's own wind, when that is stronger).
        keys: the viewer's key bindings of its controls (:class:`~.keys.AxisKeys`, :class:`~.keys.WalkKeys`): what
            the help shows and the keys steer; the first object with a walked anchor is where the ground camera
            stands. Empty: the object is watched, not steered.
    """

    config: type
    build: Callable
    scene_defaults: dict = field(default_factory=dict)
    summary: str = ""
    controls: tuple[str, ...] = ()
    apply_controls: Callable | None = None
    presets: dict = field(default_factory=dict)
    figures: dict[str, tuple[str, str]] = field(default_factory=dict)
    measure_figures: Callable | None = None
    figures_need_air_force: bool = False
    hud: Callable | None = None
    oscillations: dict[str, float] = field(default_factory=dict)
    caveat: Callable | None = None
    wind_limit: float = 20.0
    paper_counts: dict | None = None
    keys: tuple = ()

    def __post_init__(self) -> None:
        # a design is applied on top of the default design's values: one that leaves out a key another design sets
        # would silently keep that design's value (the flying kite's solver.chebyshev once leaked into the paper's)
        keys = {d: {(sec, k) for sec, values in p.items() for k in values} for d, p in self.presets.items()}
        for design, have in keys.items():
            for other, want in keys.items():
                if want - have:
                    missing = ", ".join(f"{sec}.{k}" for sec, k in sorted(want - have))
                    raise ValueError(f"preset {design!r} leaves out {missing}, which preset {other!r} sets")
        for binding in self.keys:  # a key bound to a control the object does not have would do nothing, silently
            if binding.control not in self.controls:
                raise ValueError(f"a key binding steers {binding.control!r}, which is not one of {self.controls}")


DEFAULT_OBJECT = "flag"
"""The object of a scene that names none (``scene.object``)."""
MESH = "mesh"
"""The kind built from a mesh file (:mod:`warpsim.objects.mesh`): what ``warpsim export`` writes a design as."""

OBJECTS: dict[str, ObjectSpec] = {
    DEFAULT_OBJECT: ObjectSpec(
        config=flag.FlagConfig,
        build=flag.build_flag,
        scene_defaults={"wind": {"velocity": [4.0, 0.5, 0.0]}},
        summary="stiff woven sheet nailed along a pole, in wind (the paper's cloth, slide 15: --set flag.design=paper)",
        presets=flag.PRESETS,
        figures=flag.FLAG_FIGURES,
        measure_figures=flag.flag_figures,
        hud=flag.flag_hud,
        oscillations={"flap": 0.01},  # a flap under 1 cm is jitter
        caveat=flag.flag_caveat,
    ),
    "hang-glider": ObjectSpec(
        config=hang_glider.HangGliderConfig,
        build=hang_glider.build_hang_glider,
        paper_counts=hang_glider.PAPER_COUNTS,
        # mass splitting: the plain per-particle average does not conserve angular momentum between the
        # heavy pilot and the light frame, and that spurious torque, not the air, would decide the pitch
        scene_defaults={
            "wind": {"velocity": [0.0, 0.0, 0.0]},
            "terrain": {"kind": "procedural"},
            "solver": {"mass_splitting": True},
        },
        summary="flex wing with a strap-hung pilot on a control bar (the paper's, Section 6: "
        "--set hang_glider.design=paper); steer with pitch/roll",
        controls=("pitch", "roll"),
        apply_controls=hang_glider.apply_controls,
        presets=hang_glider.PRESETS,
        figures=glider_flight.GLIDER_FIGURES,
        measure_figures=glider_flight.glider_figures,
        hud=glider_flight.glider_hud,
        keys=weight_shift_keys("hang glider"),
        wind_limit=15.0,  # above this no hang glider is flown (its trim speed is 11-12 m/s)
    ),
    "kite": ObjectSpec(
        config=kite.KiteConfig,
        build=kite.build_kite,
        paper_counts=kite.PAPER_COUNTS,
        # mass splitting: the paper's plain average does not conserve momentum between the light rope and
        # the kite, so the sticks themselves lean the rope off the kite's force balance (benchmarks/validation)
        scene_defaults={"wind": {"velocity": [6.0, 0.0, 0.0]}, "solver": {"mass_splitting": True}},
        summary="delta kite with keel on a particle rope; move the ground end with anchor (paper Section 7)",
        controls=("anchor",),
        apply_controls=kite.apply_controls,
        presets=kite.PRESETS,
        figures=kite.KITE_FIGURES,
        measure_figures=kite.kite_figures,
        hud=kite.kite_hud,
        keys=(line_walk_keys("kite", "sail"),),
        wind_limit=12.0,  # a delta kite's upper wind range (Beaufort 5-6)
    ),
    "parachute": ObjectSpec(
        config=parachute.ParachuteConfig,
        build=parachute.build_parachute,
        # 2.5 ms: at the solver's 10 ms and 55 iterations the flat canopy's swing is not converged (rms 17.2 deg
        # against 13.25, its largest swing 7.7 % short; more iterations mend the first, not the second); at 2.5 ms
        # its descent and swing lie within 2.4 % of their converged values at 12-14x real time (docs/validation.md)
        scene_defaults={"wind": {"velocity": [0.0, 0.0, 0.0]}, "solver": {"dt": 0.0025}},
        summary="round canopy of rings, lines, heavy person; hoop = true keeps it open (paper Section 8)",
        figures=parachute.PARACHUTE_FIGURES,
        measure_figures=parachute.parachute_figures,
        hud=parachute.parachute_hud,
    ),
    MESH: ObjectSpec(
        config=mesh.MeshConfig,
        build=mesh.build_mesh,
        scene_defaults={
            "wind": {"velocity": [6.0, 0.0, 0.0]},
            "solver": {"mass_splitting": True},
            "air": {"model": "sail"},
        },
        summary="your own design from a mesh file (mesh.file) with its parts (spars, nails, a line, point masses) or "
        "an export's structure file (mesh.structure)",
        controls=("pitch", "roll", "anchor"),
        apply_controls=mesh.apply_controls,
        figures=mesh.MESH_FIGURES,
        measure_figures=mesh.mesh_figures,
        hud=mesh.mesh_hud,
        keys=(
            *weight_shift_keys("your design's weight shift", active=lambda record: len(record.controlled_sticks()) > 0),
            line_walk_keys("your design", "cloth"),
        ),
        wind_limit=12.0,
    ),
}


def section(kind: str) -> str:
    """Descriptor section name of an object kind (``hang-glider`` -> ``hang_glider``)."""
    return kind.replace("-", "_")


def config_of_section(section_name: str):
    """The config dataclass of an object's descriptor section (``hang_glider`` -> its config), or None."""
    for kind, spec in OBJECTS.items():
        if section(kind) == section_name:
            return spec.config
    return None


def control_names(kinds) -> tuple[str, ...]:
    """The controls a scene of objects of ``kinds`` accepts: theirs, each once, then ``wind`` (every scene's)."""
    names: list[str] = []
    for kind in kinds:
        names += [c for c in OBJECTS[kind].controls if c not in names]
    return (*names, "wind")
