"""Typed settings of a scene: the one place where every default, unit and bound is written.

Each section of a scene descriptor (``[scene]``, ``[solver]``, ``[air]``, ``[wind]``, ``[terrain]``,
``[ground]``, and one per object) is a keyword-only dataclass here or beside its object's builder. A field's
bounds and choices sit in its metadata (:func:`number`, :func:`choice`), so that the descriptor's defaults,
its checks and the Python API (``SolverVerlet(model, SolverConfig(iterations=40))``) cannot drift apart:
:mod:`warpsim.scene.descriptor` derives its tables from these classes, and each class checks its values when made.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from dataclasses import dataclass, field
from typing import Any

from .kernels.aero import AeroModel
from .kernels.collision import CollisionMode

GRAVITY = 9.80665
"""Standard gravity [m/s^2] (slide 14; the paper's text misprints 9.80655)."""

AIR_DENSITY = 1.294217666
"""Air density [kg/m^3] used by the paper (slide 14): what its designs' presets fix ``[air] density`` to."""
STANDARD_AIR = 0.0
"""``[air] density`` that means the International Standard Atmosphere's density at each world's altitude (the
default; :mod:`warpsim.physics.atmosphere`)."""


@dataclass(frozen=True)
class Bounds:
    """Allowed range of a number: ``low`` and ``high`` (None = unbounded), each end open or closed."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False

    def violation(self, value) -> str | None:
        """What ``value`` breaks (``"must be > 0"``), or None when it is inside."""
        if self.low is not None and (value < self.low or (self.low_open and value == self.low)):
            return f"must be {'>' if self.low_open else '>='} {self.low}"
        if self.high is not None and (value > self.high or (self.high_open and value == self.high)):
            return f"must be {'<' if self.high_open else '<='} {self.high}"
        return None


POSITIVE = Bounds(0.0, low_open=True)
NON_NEGATIVE = Bounds(0.0)


def number(default, bounds: Bounds | None = None):
    """A dataclass field holding a number (or a tuple of numbers) with its ``bounds``."""
    return field(default=default, metadata={"bounds": bounds})


def choice(default: enum.Enum | str, options: type[enum.Enum] | tuple[str, ...]):
    """A dataclass field holding one of ``options``: an enum's members (written lower-case in a descriptor)
    or plain strings."""
    return field(default=default, metadata={"choices": options})


def field_bounds(cls, name: str) -> Bounds | None:
    """The :class:`Bounds` of field ``name`` of config class ``cls``, or None."""
    for f in dataclasses.fields(cls):
        if f.name == name:
            return f.metadata.get("bounds")
    return None


def field_entries(cls, name: str):
    """The parser of field ``name`` of ``cls`` when it holds a list of tables (``entries`` in its metadata: a
    callable that raises ``ValueError`` on bad entries), or None."""
    for f in dataclasses.fields(cls):
        if f.name == name:
            return f.metadata.get("entries")
    return None


def field_choices(cls, name: str) -> tuple[str, ...] | None:
    """The names a descriptor may give field ``name`` of ``cls`` (an enum's members lower-case), or None."""
    for f in dataclasses.fields(cls):
        if f.name == name:
            options = f.metadata.get("choices")
            if isinstance(options, type) and issubclass(options, enum.Enum):
                return tuple(m.name.lower() for m in options)
            return options
    return None


def plain(value):
    """A value as a descriptor (and a TOML writer) holds it: enums as lower-case names, tuples as lists, NumPy
    scalars as Python numbers, through dicts and lists."""
    if isinstance(value, enum.Enum):
        return value.name.lower()
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):  # a NumPy scalar
        return value.item()
    return value


def as_section(config) -> dict[str, Any]:
    """A config dataclass as a descriptor section (a dict of TOML-ready values)."""
    return {f.name: plain(getattr(config, f.name)) for f in dataclasses.fields(config)}


def from_section(cls, values: dict[str, Any]):
    """Make config class ``cls`` from a validated descriptor section (lists become tuples, names enums)."""
    kwargs = {}
    for f in dataclasses.fields(cls):
        if f.name in values:
            v = values[f.name]
            kwargs[f.name] = tuple(v) if isinstance(v, list) else v
    return cls(**kwargs)


class Checked:
    """Mixin of the config dataclasses: on creation, names become enum members and every bounded field and
    choice is checked (``ValueError`` naming the field)."""

    def __post_init__(self):
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            options = f.metadata.get("choices")
            if options is not None:
                value = _choose(type(self).__name__, f.name, value, options)
                object.__setattr__(self, f.name, value)
            bounds = f.metadata.get("bounds")
            if bounds is not None:
                for v in value if isinstance(value, tuple) else (value,):
                    if isinstance(v, float) and not math.isfinite(v):
                        raise ValueError(f"{f.name} must be finite, got {v}")
                    problem = bounds.violation(v)
                    if problem:
                        raise ValueError(f"{f.name} {problem}, got {v!r}")


def _choose(owner: str, name: str, value, options):
    if isinstance(options, type) and issubclass(options, enum.Enum):
        if isinstance(value, options):
            return value
        if isinstance(value, str) and value.upper() in options.__members__:
            return options[value.upper()]
        names = ", ".join(m.name.lower() for m in options)
    else:
        if value in options:
            return value
        names = ", ".join(options)
    raise ValueError(f"{name} must be one of {names}, got {value!r}")


@dataclass(frozen=True, kw_only=True)
class SceneConfig(Checked):
    """``[scene]``: which object, for how long, how often a frame.

    Attributes:
        object: the object kind (a name of :data:`warpsim.objects.registry.OBJECTS`; the scene layer names
            :data:`~warpsim.objects.registry.DEFAULT_OBJECT` where a scene names none).
        seconds: simulated time a run lasts [s] (> 0).
        fps: output frames per simulated second [1/s], as near as whole steps make it: a frame every
            ``round(1 / (fps * dt))`` steps (30 at dt 0.005 is every 7 steps, 28.6 frames a second).
    """

    object: str = ""
    seconds: float = number(10.0, POSITIVE)
    fps: float = number(30.0, Bounds(1e-6, 1e6))

    def steps_per_frame(self, dt: float) -> int:
        """Solver steps of ``dt`` [s] in one frame (at least 1)."""
        return max(1, int(round(1.0 / (self.fps * dt))))


@dataclass(frozen=True, kw_only=True)
class SolverConfig(Checked):
    """``[solver]``: the integrator and its constraint iterations.

    Attributes:
        method: ``verlet`` (the paper's: Verlet + Jacobi-averaged sticks) or ``euler`` (mass-spring comparison).
        dt: time step [s].
        iterations: Jacobi constraint iterations per step (paper: 40-55).
        relaxation: over-relaxation factor on the averaged correction (1.0 = the paper), in (0, 2).
        chebyshev: estimated spectral radius ``rho`` in [0, 1) of one Jacobi iteration for Chebyshev
            semi-iterative acceleration (Wang 2015); 0 = plain Jacobi, the paper. Same cost per iteration.
        mass_splitting: split each particle's mass over its sticks so that constraints conserve momentum
            (see :mod:`warpsim.physics.kernels.constraints`); False = the paper's plain average.
        keep_momentum: after the projection, give each free body (the particles sticks connect, none nailed) back
            the linear and angular momentum the projection's numerical error took or gave
            (:mod:`warpsim.physics.kernels.momentum`); False = the paper's projection alone.
        damping: fraction of the velocity removed per step, in [0, 1) (0 = none, the paper).
        max_stretch: blow-up limit on a stick's relative stretch ``|l - r|/r`` (0 = no limit).
        control_rate: the fastest a control stick's rest length moves to a new control's value [m/s] (the hang
            glider's arms: 0.8 m/s takes the pilot across the bar's full roll travel, 0.4 m, in about 0.5 s, as
            the viewer's keys ramp); 0 = at once.
        nail_rate: the fastest a controlled nail (the kite's anchor) moves to a new control's place [m/s] (2 m/s, a
            brisk walk); 0 = at once.
        spring_stiffness: spring constant of every stick [N/m] (``euler`` only).
        spring_damping: spring damping [N s/m] (``euler`` only).
    """

    method: str = choice("verlet", ("verlet", "euler"))
    dt: float = number(0.01, Bounds(1e-7, 1.0))
    iterations: int = number(55, Bounds(1, 10000))
    relaxation: float = number(1.0, Bounds(0.0, 2.0, low_open=True, high_open=True))
    chebyshev: float = number(0.95, Bounds(0.0, 1.0, high_open=True))
    mass_splitting: bool = False
    keep_momentum: bool = True
    damping: float = number(0.0, Bounds(0.0, 1.0, high_open=True))
    max_stretch: float = number(1.0, NON_NEGATIVE)
    control_rate: float = number(0.8, NON_NEGATIVE)
    nail_rate: float = number(2.0, NON_NEGATIVE)
    spring_stiffness: float = number(5000.0, POSITIVE)
    spring_damping: float = number(5.0, NON_NEGATIVE)

    def __post_init__(self):
        super().__post_init__()
        if isinstance(self.iterations, bool) or int(self.iterations) != self.iterations:
            raise ValueError(f"iterations must be a whole number >= 1, got {self.iterations}")


@dataclass(frozen=True, kw_only=True)
class AirConfig(Checked):
    """``[air]``: how the air pushes on the triangles (see :mod:`warpsim.physics.kernels.aero`).

    Attributes:
        model: the air-force law, :class:`~warpsim.physics.kernels.aero.AeroModel` (``paper``, ``plate``, ``sail``,
            ``vortex``).
        scale: multiplier on the air force (1 = the model as written; 0 = no air).
        density: 0 (the default) = the International Standard Atmosphere's density at each world's altitude, every
            step (:mod:`warpsim.physics.atmosphere`), with ``elevation`` and ``temperature_offset``; a positive
            number fixes the density [kg/m^3] for the whole flight (the paper designs' presets fix the paper's
            :data:`AIR_DENSITY`, the air its four objects were built in).
        elevation: altitude above mean sea level [m] of the scene's z = 0 (the terrain's and the objects' heights
            add to it).
        temperature_offset: the day's temperature off the standard atmosphere's at every altitude [K] (ISA+15 is a
            hot day; the pressure stays the standard's).
        vortex_interval: ``vortex`` law: how often [s] the lattice's influence matrix is rebuilt and factorised
            (0 = every step); the circulations are solved from those factors every step
            (:mod:`warpsim.physics.kernels.vortex`).
        wake: ``vortex`` law: ``steady`` (a quasi-steady wake along the relative wind of the moment) or ``shed``
            (a wake shed from the trailing edges over time and carried by the wind: the lift builds up and lags as
            in unsteady flow, :mod:`warpsim.physics.kernels.wake`).
        wake_rows: ``shed`` wake: rows of vortex rings kept behind each trailing edge (the oldest row ends in
            semi-infinite legs along the relative wind).
        wake_interval: ``shed`` wake: how often [s] a row is shed (rows lie ``wake_interval`` times the airspeed
            apart; at most one a step).
    """

    model: AeroModel = choice(AeroModel.PAPER, AeroModel)
    scale: float = number(1.0, NON_NEGATIVE)
    density: float = number(0.0, Bounds(0.0, 100.0))
    elevation: float = number(0.0, Bounds(-2000.0, 20000.0))
    temperature_offset: float = number(0.0, Bounds(-70.0, 50.0))
    vortex_interval: float = number(0.1, Bounds(0.0, 10.0))
    wake: str = choice("steady", ("steady", "shed"))
    wake_rows: int = number(40, Bounds(1, 2000))
    wake_interval: float = number(0.02, Bounds(0.0, 10.0, low_open=True))

    def __post_init__(self):
        super().__post_init__()
        if isinstance(self.wake_rows, bool) or int(self.wake_rows) != self.wake_rows:
            raise ValueError(f"wake_rows must be a whole number >= 1, got {self.wake_rows}")


@dataclass(frozen=True, kw_only=True)
class WindConfig(Checked):
    """``[wind]``: the wind at the start, its growth with height and its gusts (see :mod:`warpsim.scene.controls`).

    Attributes:
        velocity: wind [m/s] at ``reference_height`` (3 numbers).
        shear_exponent: power-law shear exponent (0 = the same wind at every height; ~0.14 over open land).
        reference_height: height above the terrain [m] where the wind equals ``velocity``.
        gust_intensity: gusts' standard deviation as a fraction of the mean speed (0 = steady).
        gust_period: gusts' correlation time [s].
        gust_seed: seed of the gusts' random numbers.
        turbulence_intensity: standard deviation of the frozen turbulence's every component over the wind's speed at
            the reference height (0 = none; IEC 61400-1's class A is 0.16 at 15 m/s; see
            :mod:`warpsim.physics.turbulence`).
        turbulence_length: the turbulence's longitudinal integral length scale [m] (von Kármán's; IEC 61400-1's
            isotropic model takes 3.5 x 0.7 x the height below 60 m: 24.5 m at 10 m).
        turbulence_seed: where the world enters the scene's turbulence field.
    """

    velocity: tuple[float, float, float] = number((4.0, 0.5, 0.0), Bounds(-200.0, 200.0))
    shear_exponent: float = 0.0
    reference_height: float = number(10.0, POSITIVE)
    gust_intensity: float = number(0.0, NON_NEGATIVE)
    gust_period: float = number(2.0, POSITIVE)
    gust_seed: int = number(0, NON_NEGATIVE)
    turbulence_intensity: float = number(0.0, Bounds(0.0, 1.0))
    turbulence_length: float = number(24.5, Bounds(0.5, 2000.0))
    turbulence_seed: int = number(0, NON_NEGATIVE)


@dataclass(frozen=True, kw_only=True)
class TerrainConfig(Checked):
    """``[terrain]``: the heightfield under everything (see :class:`warpsim.physics.terrain.Heightfield`).

    Attributes:
        kind: ``flat``, ``procedural`` (seeded hills) or ``file`` (heights from a .npy array).
        size: side of the square terrain [m].
        height: base height [m].
        amplitude: peak height of procedural hills above or below the base [m].
        seed: seed of procedural hills.
        file: path of the .npy array of heights [m] (``kind = "file"``).
    """

    kind: str = choice("flat", ("flat", "procedural", "file"))
    size: float = number(1000.0, Bounds(0.0, 1e7, low_open=True))
    height: float = number(0.0, Bounds(-1e5, 1e5))
    amplitude: float = number(40.0, Bounds(-1e4, 1e4))
    seed: int = number(0, NON_NEGATIVE)
    file: str = ""


@dataclass(frozen=True, kw_only=True)
class GroundConfig(Checked):
    """``[ground]``: how particles meet the terrain (see :mod:`warpsim.physics.kernels.collision`).

    Attributes:
        collision: :class:`~warpsim.physics.kernels.collision.CollisionMode`: ``normal`` (push out along the terrain
            normal, with friction) or ``clamp`` (the paper's vertical clamp).
        friction: Coulomb-like friction coefficient (dimensionless, >= 0).
    """

    collision: CollisionMode = choice(CollisionMode.NORMAL, CollisionMode)
    friction: float = number(0.5, NON_NEGATIVE)


SECTIONS: dict[str, type] = {
    "scene": SceneConfig,
    "solver": SolverConfig,
    "air": AirConfig,
    "wind": WindConfig,
    "terrain": TerrainConfig,
    "ground": GroundConfig,
}
"""Descriptor section -> its config class (the object's own section comes from the registry)."""
