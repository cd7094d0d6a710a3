"""The sections of a configuration (``[rod]``, ``[floor]``, ...): frozen dataclasses whose
fields are checked against the key specification (``keys.FIELDS``) on creation.

The defaults are written here, once; each field's meaning, unit and range are written once
in ``keys.FIELDS``, and each section's documentation lists them from there.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

from .errors import ConfigError
from .keys import FIELDS

__all__ = ["Section", "RodConfig", "FloorConfig", "GravityConfig", "InitialConfig",
           "TimeConfig", "OutputConfig", "SECTIONS", "check_dt_range"]

_S = TypeVar("_S", bound=type)


def check_dt_range(dt_min: float, dt_max: float | None) -> None:
    """Refuse ``time.dt_min`` not below ``time.dt_max``.

    Raises
    ------
    ConfigError
        Naming ``time.dt_min`` and the range.
    """
    if dt_max is not None and dt_min >= dt_max:
        raise ConfigError(f"time.dt_min = {dt_min!r} is out of range (float > 0 and "
                          f"< time.dt_max = {dt_max!r})")


class Section:
    """A config section: its fields are checked against ``FIELDS[SECTION]`` on creation."""

    SECTION: ClassVar[str] = ""

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):   # type: ignore[arg-type]
            spec = FIELDS[self.SECTION][f.name]
            key = f"{self.SECTION}.{f.name}"
            value = spec.coerce(key, getattr(self, f.name))   # ConfigError naming the key
            object.__setattr__(self, f.name, value)


def _documented(cls: _S) -> _S:
    """Append to a section's docstring its parameters, from ``FIELDS`` (meaning, unit,
    range) and the dataclass (default): written once, shown by ``help()``."""
    lines = ["", "    Parameters", "    ----------"]
    defaults = cls()
    for name, spec in FIELDS[cls.SECTION].items():      # type: ignore[attr-defined]
        kind = {"int": "int", "float": "float", "str": "str", "bool": "bool",
                "times": "tuple of float"}[spec.kind]
        lines.append(f"    {name} : {kind}{' or None' if spec.optional else ''}")
        unit = f" [{spec.unit}]" if spec.unit and spec.unit != "1" else ""
        lines.append(f"        {spec.meaning[:1].upper()}{spec.meaning[1:]}{unit}; "
                     f"{spec.describe()}; default {getattr(defaults, name)!r}.")
    lines += ["", "    Raises", "    ------", "    ConfigError",
              "        A field outside its range, naming the key and the range.", ""]
    cls.__doc__ = (cls.__doc__ or "").rstrip() + "\n" + "\n".join(lines)
    return cls


@_documented
@dataclass(frozen=True)
class RodConfig(Section):
    """The rod: ``N`` segments, elasticity κ, beam regularisation γ, viscosity μ, and its
    stress law (``rodjit.laws.law_names("rod")``)."""

    SECTION: ClassVar[str] = "rod"

    N: int = 5
    kappa: float = 100.0
    gamma: float = 0.0
    mu: float = 0.0
    law: str = "aiki-kosugi"


@_documented
@dataclass(frozen=True)
class FloorConfig(Section):
    """The floor: stiffness κ_b, bending limit β, its stress law
    (``rodjit.laws.law_names("floor")``) and its Hunt–Crossley damping α (0: none)."""

    SECTION: ClassVar[str] = "floor"

    kappa_b: float = 1000.0
    beta: float = 0.05
    law: str = "aiki-kosugi"
    damping: float = 0.0


@_documented
@dataclass(frozen=True)
class GravityConfig(Section):
    """Signed acceleration along +u; −9.81 pulls down."""

    SECTION: ClassVar[str] = "gravity"

    g: float = -9.81


@_documented
@dataclass(frozen=True)
class InitialConfig(Section):
    """Initial state: bottom height (above ``-floor.beta``, checked by ``Config``), uniform
    velocity, uniform pre-strain; or, with ``impact_speed`` set, the uniform velocity that
    brings the bottom to the floor at that speed (``model.system.start_velocity``)."""

    SECTION: ClassVar[str] = "initial"

    height: float = 1.0
    velocity: float = 0.0
    strain: float = 0.0
    impact_speed: float | None = None


@_documented
@dataclass(frozen=True)
class TimeConfig(Section):
    """Time span and stepping; ``dt`` set means fixed steps, unset means adaptive.

    ``integrator`` is ``"auto"`` (``Config.resolve`` picks one from the registry's table)
    or one of ``INTEGRATORS`` (see *Choosing an integrator*); ``control``
    (``verlet`` and ``semi-implicit``) is ``"tolerance"`` (steps from ``rtol``/``atol``,
    stability as a cap) or ``"cfl"`` (``cfl`` times the stability limit); ``dt_min`` must
    be below ``dt_max``."""

    SECTION: ClassVar[str] = "time"

    t_end: float = 5.0
    integrator: str = "auto"
    cfl: float = 0.05
    control: str = "tolerance"
    dt_max: float | None = None
    dt_min: float = 1e-12
    dt: float | None = None
    rtol: float = 1e-6
    atol: float = 1e-9
    stop_after_bounces: int = 0
    stop_at_rest: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        check_dt_range(self.dt_min, self.dt_max)


@_documented
@dataclass(frozen=True)
class OutputConfig(Section):
    """Output schedule (simulated seconds between samples) and HDF5 compression.

    ``interpolate`` true (the default): the integrators with a dense output, ``dp54``,
    ``dop853`` and ``radau5``, step toward ``time.t_end`` only and give each output time
    inside a step by their continuous extension (4th order for ``dp54``, 7th for
    ``dop853``, the collocation polynomial of stage order 3 for ``radau5``), so the output
    schedule costs them no steps; false: their steps land on every output time, so each row
    is the state of a step (the second-order schemes and ``energy`` always land, and so
    does any integrator under a fixed ``time.dt``).  Rows at ``time.t_end`` are always a
    step's own state.

    ``times`` (empty by default) lists the snapshot times themselves, as ``t_eval`` does
    for SciPy's ``solve_ivp``: the snapshots are taken at those times, by the same rule
    (dense output or landing), and ``snapshot_interval`` is not used; the diagnostics
    keep their own interval (the bounce and first-impact observables are read from
    them).

    ``observer`` names a registered observer (``rodjit.observers``; "none", the default:
    none), compiled code that watches every accepted step and gives named values."""

    SECTION: ClassVar[str] = "output"

    snapshot_interval: float = 0.005
    diagnostics_interval: float = 0.001
    times: tuple[float, ...] = ()
    observer: str = "none"
    compression: str = "none"
    interpolate: bool = True


SECTIONS: dict[str, type[Section]] = {
    "rod": RodConfig, "floor": FloorConfig, "gravity": GravityConfig,
    "initial": InitialConfig, "time": TimeConfig, "output": OutputConfig}


def section_dict(section: Any) -> dict[str, Any]:
    """A section's fields as a dict (``dataclasses.asdict``)."""
    return dataclasses.asdict(section)
