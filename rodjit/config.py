"""Validated, frozen run configuration, loadable from TOML and overridable by dotted keys.

Every field is declared once in ``_FIELDS`` with its type, allowed range, meaning and unit
(the default is the dataclass's): one source for the error messages, ``rodjit config``
(``commented_toml``, ``key_lines``), the file attributes and the documentation.  Bad values
raise ``ValueError`` naming the key and the range, at the moment they enter.  Numbers may be
Python or NumPy numbers; a TOML file is strict (a quoted number is an error), while
``override`` also takes strings in TOML syntax, as the command line's ``--set`` gives them.
"""
from __future__ import annotations

import dataclasses
import difflib
import errno
import math
import numbers
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, Mapping

from .stepping.registry import NAMES as INTEGRATORS   # the one list of integrator names
from .stepping.registry import get as _registry_get


def _registry_names() -> tuple[str, ...]:
    """The integrators registered now (``registry.register`` adds to the built-in ones)."""
    from .stepping import registry
    return registry.NAMES

# time.control of the kick–drift–kick integrators: "tolerance" (steps from time.rtol and
# time.atol, stability as a cap) or "cfl" (time.cfl × the stability limit, no estimate)
CONTROLS = ("tolerance", "cfl")
# keys that a stored configuration may lack (written before they existed), with the value
# that reproduces what such a run did
STORED_DEFAULTS = {"time.control": "cfl", "output.interpolate": False}


class MissingFile(ValueError, FileNotFoundError):
    """A file rodjit was asked to read does not exist: a ``FileNotFoundError`` (what
    ``open`` raises) that is also a ValueError (a bad argument: one line, exit code 2).

    Parameters
    ----------
    path : str or Path
        The missing file.
    what : str, optional
        What the file is, for the message (``"configuration file "``).
    """

    def __init__(self, path, what: str = ""):
        message = f"{what}{str(path)!r} does not exist"
        super().__init__(message)
        self.errno, self.strerror, self.filename = errno.ENOENT, message, str(path)
        self._what = what

    def __str__(self) -> str:
        return self.args[0]

    def __reduce__(self):
        return type(self), (self.filename, self._what)


class ModelWarning(UserWarning):
    """A configuration that runs, but whose results mean less than a user would expect."""


# The texts of ``Config.warnings`` (tests and the convergence tool use them too).
SHOCK_WARNING = (
    "rod.mu = 0 and rod.gamma = 0: compression waves steepen into shocks that this "
    "discretisation does not resolve, so first-bounce observables (restitution, contact "
    "time, penetration, strain) have no continuum limit as rod.N grows; energy and "
    "long-run statistics remain meaningful (set rod.gamma > 0 or rod.mu > 0 for a "
    "convergent first bounce)")
# verlet's Crank–Nicolson viscous sub-step is split off the kicks: above this μ its error
# is set by its viscous step cap, not by its tolerance (``registry.Scheme.viscous_mu_max``)
VERLET_MU_MAX = _registry_get("verlet").viscous_mu_max


def _viscous_warning(name: str, mu_max: float) -> str:
    return (f"time.integrator = {name!r} with rod.mu > {mu_max:g}: its viscous sub-step, "
            "split off the kicks, limits the step to mu*dt*4/h^2 <= 2*time.cfl (steps grow "
            "like mu*N^2) and still misses 1e-4 on first-bounce observables; use 'energy' "
            "or 'semi-implicit'")


VERLET_WARNING = _viscous_warning("verlet", VERLET_MU_MAX)

__all__ = ["Config", "RodConfig", "FloorConfig", "GravityConfig", "InitialConfig",
            "TimeConfig", "OutputConfig", "INTEGRATORS", "CONTROLS", "ModelWarning", "MissingFile",
           "valid_keys", "field_spec", "key_lines", "parse_value", "CROSS_CHECKS",
           "RUN_CHECKS"]

COMPRESSIONS = ("gzip", "lzf", "none")


class _Spec:
    """Type and range of one configuration field; ``check`` returns an error or None."""

    def __init__(self, kind: str, rng: str = "", check=None, optional: bool = False,
                 choices: tuple[str, ...] | None = None, *, meaning: str, unit: str = ""):
        self.kind, self.rng, self.check, self.optional = kind, rng, check, optional
        self._choices = choices  # a tuple, or a function giving it (names registered later)
        self.meaning = meaning   # what the key sets: for comments, listings and file attributes
        self.unit = unit         # UDUNITS string (docs/MODEL.md "Units"); "" for text and
                                 # boolean keys

    @property
    def choices(self) -> tuple[str, ...] | None:
        """The allowed values (None: any of the kind); registries answer at call time."""
        return self._choices() if callable(self._choices) else self._choices

    def coerce(self, key: str, value: Any) -> Any:
        """``value`` checked and converted to the field's Python type (NumPy integers and
        floats as int and float; booleans, NumPy's included, are not numbers here)."""
        if value is None:
            if self.optional:
                return None
            raise ValueError(f"{key} must be set ({self.describe()})")
        if isinstance(value, str) and self.kind != "str":
            raise ValueError(_quoted_error(key, value, self))
        is_bool = isinstance(value, bool) or type(value).__name__ in ("bool_", "bool")
        if self.kind == "bool":
            if not is_bool:
                raise ValueError(f"{key} = {value!r} is not a boolean ({self.describe()})")
            value = bool(value)
        elif self.kind == "int":
            if is_bool or not isinstance(value, numbers.Real):
                raise ValueError(f"{key} = {value!r} is not an integer ({self.describe()})")
            if isinstance(value, numbers.Integral):
                value = int(value)
            elif float(value).is_integer():
                value = int(float(value))
            else:
                raise ValueError(f"{key} = {value!r} is not an integer ({self.describe()})")
        elif self.kind == "float":
            if is_bool or not isinstance(value, numbers.Real):
                raise ValueError(f"{key} = {value!r} is not a number ({self.describe()})")
            try:
                value = float(value)
            except OverflowError:      # an integer beyond any float (hundreds of digits)
                raise ValueError(f"{key} = {_shown(value)} is out of range "
                                 f"({self.describe()})") from None
            if not math.isfinite(value):
                raise ValueError(f"{key} = {value!r} is not finite ({self.describe()})")
        elif self.kind == "str":
            if not isinstance(value, str):
                raise ValueError(f"{key} = {value!r} is not a string ({self.describe()})")
            if self.choices is not None and value not in self.choices:
                raise ValueError(f"{key} = {value!r} is not allowed ({self.describe()})")
        if self.check is not None and not self.check(value):
            raise ValueError(f"{key} = {_shown(value)} is out of range ({self.describe()})")
        return value

    def comment(self, default: Any) -> str:
        """One line of ``rodjit config``: meaning, unit, default and allowed values."""
        unit = f"; unit {self.unit}" if self.unit and self.unit != "1" else (
            "; dimensionless" if self.unit == "1" else "")
        shown = "unset" if default is None else _toml_value(default)
        return f"{self.meaning}{unit}; default {shown}; {self.describe()}"

    def describe(self) -> str:
        if self.choices is not None:
            text = "one of " + ", ".join(repr(c) for c in self.choices)
        elif self.kind == "bool":
            text = "true or false"
        else:
            text = f"{self.kind} {self.rng}".strip()
        return text + (", or unset" if self.optional else "")


def _shown(value) -> str:
    """``repr(value)``, an integer of many digits shortened (its digits counted)."""
    text = repr(value)
    if isinstance(value, int) and len(text) > 24:
        return f"{text[:12]}...({len(text.lstrip('-'))} digits)"
    return text


def _quoted_error(key: str, value: str, spec: "_Spec") -> str:
    """The error for text where a number is expected: a quoted number says so."""
    try:
        number = tomllib.loads(f"v = {value.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        number = None
    if spec.kind == "bool":
        if isinstance(number, bool):
            return (f"{key} = {value!r} is a quoted boolean; write {value.strip()} without "
                    f"quotes ({spec.describe()})")
        return f"{key} = {value!r} is not a boolean ({spec.describe()})"
    if isinstance(number, (int, float)) and not isinstance(number, bool):
        return (f"{key} = {value!r} is a quoted number; write {value.strip()} without quotes "
                f"({spec.describe()})")
    what = "an integer" if spec.kind == "int" else "a number"
    if number_with_unit(value) is not None:
        unit = ("; it is dimensionless" if spec.unit == "1" else
                f"; write it in {spec.unit}, without the unit" if spec.unit else "")
        return (f"{key} = {value!r} is not {what}: values are plain SI numbers without "
                f"units{unit} (see docs/units.md; {spec.describe()})")
    return f"{key} = {value!r} is not {what} ({spec.describe()})"


_NUMBER_WITH_UNIT = re.compile(
    r"^\s*([-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?)\s*[A-Za-zµμΩ°%][^=,]*$")


def number_with_unit(text: str) -> str | None:
    """The number of ``text`` when it is a number followed by a unit (``"2s"``, ``"1e3 N"``,
    ``"5 mm"``), else None.

    Parameters
    ----------
    text : str
        A value as typed.

    Returns
    -------
    str or None
        The number as written, without its unit.
    """
    m = _NUMBER_WITH_UNIT.match(text)
    return m.group(1) if m else None


def _pos(x):
    return x > 0


def _nonneg(x):
    return x >= 0


_FIELDS: dict[str, dict[str, _Spec]] = {
    "rod": {
        "N": _Spec("int", "in [1, 10000000]", lambda n: 1 <= n <= 10_000_000,
                   meaning="number of rod segments (N + 1 nodes)", unit="1"),
        "kappa": _Spec("float", "> 0", _pos, meaning="elastic modulus kappa of the rod",
                       unit="N"),
        "gamma": _Spec("float", ">= 0", _nonneg,
                       meaning="bending (beam regularisation) coefficient gamma", unit="N m2"),
        "mu": _Spec("float", ">= 0", _nonneg, meaning="viscosity mu of the rod", unit="N s"),
        "law": _Spec("str", "a registered rod law", meaning="stress law f of the rod"),
    },
    "floor": {
        "kappa_b": _Spec("float", "> 0", _pos, meaning="stiffness kappa_b of the floor",
                         unit="N"),
        "beta": _Spec("float", "> 0", _pos, unit="m",
                      meaning="bending limit beta of the floor (its stress is singular at "
                              "u_0 = -beta)"),
        "law": _Spec("str", "a registered floor law", meaning="stress law sigma_b of the floor"),
    },
    "gravity": {
        "g": _Spec("float", "finite, signed along +u (negative pulls down)",
                   meaning="gravitational acceleration along +u", unit="m s-2"),
    },
    "initial": {
        "height": _Spec("float", "> -floor.beta", meaning="initial height of the bottom end u_0",
                        unit="m"),
        "velocity": _Spec("float", "finite", meaning="initial velocity of every node",
                          unit="m s-1"),
        "strain": _Spec("float", "> -1", lambda e: e > -1.0,
                        meaning="initial uniform strain of the rod", unit="1"),
    },
    "time": {
        "t_end": _Spec("float", "> 0", _pos, meaning="time at which the run ends", unit="s"),
        "integrator": _Spec("str", choices=_registry_names, meaning="time integrator"),
        "cfl": _Spec("float", "in (0, 1]", lambda c: 0 < c <= 1, unit="1",
                     meaning="fraction of the stability limit taken as the step (verlet, "
                             "semi-implicit with time.control = 'cfl')"),
        "control": _Spec("str", choices=CONTROLS,
                         meaning="step control of verlet and semi-implicit: 'tolerance' "
                                 "(steps from rtol and atol, stability as a cap) or 'cfl' "
                                 "(time.cfl times the stability limit)"),
        "dt_max": _Spec("float", "> 0", _pos, optional=True, meaning="largest adaptive step",
                        unit="s"),
        "dt_min": _Spec("float", "> 0", _pos, meaning="smallest step before the run fails",
                        unit="s"),
        "dt": _Spec("float", "> 0 (fixed step; unset for adaptive steps)", _pos, optional=True,
                    meaning="fixed time step", unit="s"),
        "rtol": _Spec("float", "in (0, 1)", lambda r: 0 < r < 1, unit="1",
                      meaning="relative tolerance of the local error per step (every "
                              "integrator under time.control = 'tolerance')"),
        "atol": _Spec("float", "> 0", _pos, unit="m",
                      meaning="absolute tolerance of the local error per step (heights "
                              "u)"),
    },
    "output": {
        "snapshot_interval": _Spec("float", ">= 0 (0 disables snapshots)", _nonneg, unit="s",
                                   meaning="simulated time between snapshots of u and v"),
        "diagnostics_interval": _Spec("float", ">= 0 (0 disables diagnostics)", _nonneg,
                                      unit="s", meaning="simulated time between diagnostics "
                                                        "rows"),
        "compression": _Spec("str", choices=COMPRESSIONS,
                             meaning="compression of the HDF5 tables"),
        "interpolate": _Spec("bool",
                             meaning="outputs of dp54, dop853 and radau5 from the "
                                     "integrator's dense output between steps (true) or from "
                                     "steps landing on each output time (false)"),
    },
}


def field_spec(key: str) -> _Spec:
    """The spec of a dotted key: its kind, range, meaning and unit.

    Parameters
    ----------
    key : str
        A dotted configuration key, e.g. ``"rod.mu"``.

    Returns
    -------
    _Spec
        The field's specification (``kind``, ``describe()``, ``meaning``, ``unit``).

    Raises
    ------
    ValueError
        For an unknown key, naming the closest valid key.
    """
    section, _, name = key.partition(".")
    try:
        return _FIELDS[section][name]
    except KeyError:
        raise _unknown_key_error(key) from None


def key_lines() -> list[str]:
    """``rodjit config --keys``: every key with its meaning and unit, one per line.

    Returns
    -------
    list of str
        One aligned line per key of ``valid_keys()``.
    """
    width = max(len(k) for k in valid_keys())
    out = []
    for key in valid_keys():
        spec = field_spec(key)
        unit = f" [{spec.unit}]" if spec.unit else ""
        out.append(f"{key:<{width}}  {spec.meaning}{unit}")
    return out


def valid_keys() -> list[str]:
    """Every configuration key, dotted (``rod.mu``, ``floor.kappa_b``, ...).

    Returns
    -------
    list of str
        The keys in section order, as TOML files and ``--set`` name them.
    """
    return [f"{s}.{k}" for s, fields in _FIELDS.items() for k in fields]


def _unknown_section_error(section: str) -> ValueError:
    close = difflib.get_close_matches(section, list(_FIELDS), n=1, cutoff=0.5)
    hint = f"; did you mean [{close[0]}]?" if close else ""
    exc = ValueError(f"unknown configuration section [{section}]{hint} sections: "
                     + ", ".join(f"[{name}]" for name in _FIELDS))
    exc.key = section + "."
    return exc


def _unknown_key_error(key: str) -> ValueError:
    keys = valid_keys()
    name = key.rsplit(".", 1)[-1]
    # the right name in the wrong section first, then the closest spelling
    close = [k for k in keys if name and k.rsplit(".", 1)[1] == name][:1]
    close = close or difflib.get_close_matches(key, keys, n=1, cutoff=0.6)
    hint = f"; did you mean '{close[0]}'?" if close else ""
    exc = ValueError(f"unknown configuration key '{key}'{hint} valid keys: {', '.join(keys)}")
    exc.key = key
    return exc


class _Section:
    """A config section: its fields are checked against ``_FIELDS[SECTION]`` on creation."""

    SECTION = ""

    def __post_init__(self):
        for f in dataclasses.fields(self):
            spec = _FIELDS[self.SECTION][f.name]
            key = f"{self.SECTION}.{f.name}"
            try:
                value = spec.coerce(key, getattr(self, f.name))
            except ValueError as exc:
                exc.key = key          # for the line of a TOML file that set it
                raise
            object.__setattr__(self, f.name, value)


@dataclass(frozen=True)
class RodConfig(_Section):
    """The rod: ``N`` segments, elasticity κ, beam regularisation γ, viscosity μ.

    Every section checks its fields on creation.

    Parameters
    ----------
    N : int
        Number of rod segments (N + 1 nodes), in [1, 10⁷].
    kappa : float
        Elastic modulus κ of the rod [N], > 0.
    gamma : float
        Bending (beam regularisation) coefficient γ [N m²], >= 0.
    mu : float
        Viscosity μ of the rod [N s], >= 0.
    law : str
        Name of a registered rod stress law f (``rodjit.laws.law_names("rod")``).

    Raises
    ------
    ValueError
        A field outside its range, naming the key (``rod.<name>``) and the range.
    """

    SECTION: ClassVar[str] = "rod"

    N: int = 5
    kappa: float = 100.0
    gamma: float = 0.0
    mu: float = 0.0
    law: str = "aiki-kosugi"


@dataclass(frozen=True)
class FloorConfig(_Section):
    """The floor: stiffness κ_b and bending limit β.

    Parameters
    ----------
    kappa_b : float
        Stiffness κ_b of the floor [N], > 0.
    beta : float
        Bending limit β of the floor [m], > 0: its stress is singular at u_0 = −β.
    law : str
        Name of a registered floor stress law σ_b (``rodjit.laws.law_names("floor")``).

    Raises
    ------
    ValueError
        A field outside its range, naming the key and the range.
    """

    SECTION: ClassVar[str] = "floor"

    kappa_b: float = 1000.0
    beta: float = 0.05
    law: str = "aiki-kosugi"


@dataclass(frozen=True)
class GravityConfig(_Section):
    """Signed acceleration along +u; −9.81 pulls down.

    Parameters
    ----------
    g : float
        Gravitational acceleration along +u [m s⁻²], finite.

    Raises
    ------
    ValueError
        A non-finite value, naming ``gravity.g``.
    """

    SECTION: ClassVar[str] = "gravity"

    g: float = -9.81


@dataclass(frozen=True)
class InitialConfig(_Section):
    """Initial state: bottom height, uniform velocity, uniform pre-strain.

    Parameters
    ----------
    height : float
        Initial height u_0 of the bottom end [m], > −floor.beta (checked by ``Config``).
    velocity : float
        Initial velocity of every node [m s⁻¹], finite.
    strain : float
        Initial uniform strain of the rod, > −1.

    Raises
    ------
    ValueError
        A field outside its range, naming the key and the range.
    """

    SECTION: ClassVar[str] = "initial"

    height: float = 1.0
    velocity: float = 0.0
    strain: float = 0.0


@dataclass(frozen=True)
class TimeConfig(_Section):
    """Time span and stepping; ``dt`` set means fixed steps, unset means adaptive.

    Parameters
    ----------
    t_end : float
        Time at which the run ends [s], > 0.
    integrator : str
        The time integrator, one of ``INTEGRATORS`` (see *Choosing an integrator*).
    cfl : float
        Fraction of the stability limit taken as the step, in (0, 1] (``verlet`` and
        ``semi-implicit`` under ``control = "cfl"``).
    control : str
        Step control of ``verlet`` and ``semi-implicit``, one of ``CONTROLS``:
        ``"tolerance"`` (steps from ``rtol``/``atol``, stability as a cap) or ``"cfl"``.
    dt_max : float or None
        Largest adaptive step [s], > 0; None: no cap beyond the scheme's own.
    dt_min : float
        Smallest step before the run fails [s], > 0 and < ``dt_max``.
    dt : float or None
        Fixed time step [s], > 0; None (the default) for adaptive steps.
    rtol : float
        Relative tolerance of the local error per step, in (0, 1).
    atol : float
        Absolute tolerance of the local error per step (heights u) [m], > 0.

    Raises
    ------
    ValueError
        A field outside its range, or ``dt_min >= dt_max``, naming the key.
    """

    SECTION: ClassVar[str] = "time"

    t_end: float = 5.0
    integrator: str = "energy"
    cfl: float = 0.05
    control: str = "tolerance"
    dt_max: float | None = None
    dt_min: float = 1e-12
    dt: float | None = None
    rtol: float = 1e-6
    atol: float = 1e-9

    def __post_init__(self):
        super().__post_init__()
        _check_dt_range(self.dt_min, self.dt_max)


@dataclass(frozen=True)
class OutputConfig(_Section):
    """Output schedule (simulated seconds between samples) and HDF5 compression.

    Parameters
    ----------
    snapshot_interval : float
        Simulated time between snapshots of u and v [s], >= 0 (0 disables snapshots).
    diagnostics_interval : float
        Simulated time between diagnostics rows [s], >= 0 (0 disables diagnostics).
    compression : str
        Compression of the HDF5 tables, one of ``COMPRESSIONS``.
    interpolate : bool
        True (the default): the integrators with a dense output, ``dp54``, ``dop853`` and
        ``radau5``, step toward ``time.t_end`` only and give each output time inside a step
        by their continuous extension (4th order for ``dp54``, 7th for ``dop853``, the
        collocation polynomial of stage order 3 for ``radau5``), so the output schedule
        costs them no steps; False: their steps land on every output time, so each row is
        the state of a step (the second-order schemes and ``energy`` always land, and so
        does any integrator under a fixed ``time.dt``).
        Rows at ``time.t_end`` are always a step's own state.

    Raises
    ------
    ValueError
        A field outside its range, naming the key and the range.
    """

    SECTION: ClassVar[str] = "output"

    snapshot_interval: float = 0.005
    diagnostics_interval: float = 0.001
    compression: str = "none"
    interpolate: bool = True


def _check_dt_range(dt_min, dt_max) -> None:
    if dt_max is not None and dt_min >= dt_max:
        raise ValueError(f"time.dt_min = {dt_min!r} is out of range (float > 0 and "
                         f"< time.dt_max = {dt_max!r})")


def _check_height(height, beta) -> None:
    if not height > -beta:
        raise ValueError(
            f"initial.height = {height!r} is out of range (float > -floor.beta "
            f"= {-beta!r}: the bottom must start above the floor's bending limit)")


def _law_check(kind: str):
    def check(name) -> None:
        from .model.laws import get_law  # laws register themselves on import
        get_law(kind, name)
    return check


# What a Config checks beyond each key's own type and range (``_FIELDS``): the keys whose
# allowed values depend on each other, and the law names (looked up in the registry).
# ``Config`` runs every check; a sweep grid checks each key's values once and these only
# over the combinations of the swept keys they name, not over every point.
CROSS_CHECKS = ((("rod.law",), _law_check("rod")),
                (("floor.law",), _law_check("floor")),
                (("initial.height", "floor.beta"), _check_height),
                (("time.dt_min", "time.dt_max"), _check_dt_range))


def _check_tolerance_honoured(integrator, control, dt, mu) -> None:
    entry = _registry_get(integrator)
    if control == "tolerance" and dt is None and mu > entry.viscous_mu_max:
        raise ValueError(
            f"time.integrator = {integrator!r} cannot honour time.rtol/time.atol at "
            f"rod.mu = {mu:g} > {entry.viscous_mu_max:g}: its split viscous sub-step caps "
            f"the step at time.cfl*h^2/(2*mu), and that cap, not the tolerance, sets its "
            f"error; set time.control = 'cfl' and refine time.cfl, or use "
            f"time.integrator = 'semi-implicit' or 'energy'")


# What a run checks beyond ``CROSS_CHECKS`` before it steps (``Config.check_runnable``):
# configurations that are valid (a file may hold one) but that a run refuses.
RUN_CHECKS = ((("time.integrator", "time.control", "time.dt", "rod.mu"),
               _check_tolerance_honoured),)


_SECTIONS = {"rod": RodConfig, "floor": FloorConfig, "gravity": GravityConfig,
             "initial": InitialConfig, "time": TimeConfig, "output": OutputConfig}


@dataclass(frozen=True)
class Config:
    """A complete run configuration (defaults: the built-in run, the paper's first figure).

    Frozen: ``override`` returns a new configuration.  Every key is listed, with its unit,
    range and default, in the configuration reference.

    Parameters
    ----------
    rod : RodConfig
        The rod (``rod.*`` keys).
    floor : FloorConfig
        The floor (``floor.*``).
    gravity : GravityConfig
        Gravity (``gravity.g``).
    initial : InitialConfig
        The initial state (``initial.*``).
    time : TimeConfig
        Time span, integrator and step control (``time.*``).
    output : OutputConfig
        Output schedule and compression (``output.*``).

    Raises
    ------
    ValueError
        A section of the wrong type, an unregistered law, or ``initial.height`` not above
        ``-floor.beta``.

    Examples
    --------
    >>> cfg = Config().override({"rod.mu": 100.0})
    >>> cfg.rod.mu
    100.0
    """

    rod: RodConfig = field(default_factory=RodConfig)
    floor: FloorConfig = field(default_factory=FloorConfig)
    gravity: GravityConfig = field(default_factory=GravityConfig)
    initial: InitialConfig = field(default_factory=InitialConfig)
    time: TimeConfig = field(default_factory=TimeConfig)
    output: OutputConfig = field(default_factory=OutputConfig)

    def __post_init__(self):
        for name, cls in _SECTIONS.items():
            if not isinstance(getattr(self, name), cls):
                raise ValueError(f"{name} must be a {cls.__name__}")
        for keys, check in CROSS_CHECKS:
            check(*(self.get(key) for key in keys))

    # ---- construction -------------------------------------------------------------------
    def warnings(self) -> tuple[str, ...]:
        """What this configuration's results cannot be trusted for.

        Returns
        -------
        tuple of str
            One sentence per known limitation (empty: nothing known): the shock-forming
            μ = γ = 0 model, verlet at large μ.
        """
        out = []
        if self.rod.mu == 0 and self.rod.gamma == 0:
            out.append(SHOCK_WARNING)
        entry = _registry_get(self.time.integrator)
        if self.rod.mu > entry.viscous_mu_max:
            out.append(_viscous_warning(entry.name, entry.viscous_mu_max))
        return tuple(out)

    def check_runnable(self) -> None:
        """Refuse, in one line, a configuration that is valid but whose run could not keep
        its promise (``RUN_CHECKS``): under ``time.control = "tolerance"`` an integrator
        whose error above its ``viscous_mu_max`` (the registry's fact; ``verlet``: 1) is
        set by its viscous step cap, not by ``time.rtol``/``time.atol`` (verlet at
        μ = 100 misses the first restitution by the same 3.5e-5 at every rtol from 1e-3
        to 1e-7).  Runs call it before stepping; reading a file that holds such a
        configuration does not.

        Raises
        ------
        ValueError
            Such a configuration, naming the key that does set its steps.
        """
        for keys, check in RUN_CHECKS:
            check(*(self.get(key) for key in keys))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Config":
        """Build from nested and/or dotted keys.

        Parameters
        ----------
        data : Mapping
            Nested ``{"rod": {"mu": 1.0}}`` and/or dotted ``{"rod.mu": 1.0}``; missing keys
            take their defaults.

        Returns
        -------
        Config

        Raises
        ------
        ValueError
            An unknown key (naming the closest valid one) or a value out of range.
        """
        return cls().override(_flatten(data))

    @classmethod
    def from_toml(cls, path: str | Path) -> "Config":
        """Load a TOML file; missing keys take their defaults, unknown keys are errors.

        Parameters
        ----------
        path : str or Path
            The TOML file (sections ``[rod]``, ``[floor]``, ...).

        Returns
        -------
        Config

        Raises
        ------
        ValueError
            The file is missing, unreadable or not TOML, or a key is unknown or out of
            range; the message names the file or the key.
        """
        path = Path(path)
        try:
            with open(path, "rb") as fh:
                raw = fh.read()
            data = tomllib.loads(raw.decode("utf-8"))
        except FileNotFoundError:
            raise MissingFile(path, "configuration file ") from None
        except IsADirectoryError:
            raise ValueError(f"configuration file {str(path)!r} is a directory") from None
        except PermissionError:
            raise ValueError(f"configuration file {str(path)!r} is not readable") from None
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"configuration file {str(path)!r} is not valid TOML: {exc}") from None
        except UnicodeDecodeError:
            raise ValueError(f"configuration file {str(path)!r} is not a text file") from None
        try:
            return cls()._replaced(_flatten(data), text=False)
        except ValueError as exc:
            key = getattr(exc, "key", None)
            line = _toml_line(raw.decode("utf-8"), key) if key else None
            where = f"{str(path)}, line {line}" if line else str(path)
            error = ValueError(f"{where}: {exc}")
            error.key = key
            raise error from None

    @classmethod
    def from_toml_string(cls, text: str) -> "Config":
        """Read a configuration from TOML text (as ``from_toml`` reads a file).

        Parameters
        ----------
        text : str
            TOML text with sections ``[rod]``, ``[floor]``, ...; missing keys take their
            defaults.

        Returns
        -------
        Config

        Raises
        ------
        ValueError
            The text is not TOML, or a key is unknown or out of range.
        """
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"configuration is not valid TOML: {exc}") from None
        return cls()._replaced(_flatten(data), text=False)

    @classmethod
    def from_stored_toml(cls, text: str) -> "Config":
        """The configuration a file recorded (``config_toml``), as the run that wrote it ran.

        A key added to rodjit after the file was written takes the value that reproduces
        the old behaviour, not today's default: files written before ``time.control``
        existed stepped by ``time.cfl`` (``"cfl"``), so they resume bit for bit.

        Parameters
        ----------
        text : str
            The TOML text stored in a run or sweep file.

        Returns
        -------
        Config

        Raises
        ------
        ValueError
            The text is not TOML, or a key is unknown or out of range.
        """
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"configuration is not valid TOML: {exc}") from None
        flat = _flatten(data)
        for key, value in STORED_DEFAULTS.items():
            flat.setdefault(key, value)
        return cls()._replaced(flat, text=False)

    def override(self, changes: Mapping[str, Any]) -> "Config":
        """A new config with dotted keys replaced, e.g. ``{"rod.mu": 100.0}``.

        Values may be strings in TOML syntax (``"1e-3"``, ``"'verlet'"``, ``"none"``), as the
        command line's ``--set`` passes them, and NumPy numbers.

        Parameters
        ----------
        changes : Mapping
            Dotted key -> new value.

        Returns
        -------
        Config
            A new configuration; ``self`` is unchanged.

        Raises
        ------
        ValueError
            An unknown key (naming the closest valid one) or a value out of range.
        """
        return self._replaced(changes, text=True)

    def _replaced(self, changes: Mapping[str, Any], *, text: bool) -> "Config":
        """``override``; ``text``: strings for non-text keys are parsed as TOML values (else
        they are an error naming the key, as in a TOML file)."""
        # only the sections a change touches are rebuilt (and checked again); the others
        # are the same frozen objects (a sweep builds one configuration per point)
        sections: dict[str, dict[str, Any]] = {}
        for key, value in changes.items():
            if not isinstance(key, str) or "." not in key:
                raise _unknown_key_error(str(key))
            section, name = key.split(".", 1)
            if section not in _FIELDS or name not in _FIELDS[section]:
                raise _unknown_key_error(key)
            if text and isinstance(value, str) and _FIELDS[section][name].kind != "str":
                value = parse_value(key, value)
            elif text and isinstance(value, str) and _FIELDS[section][name].kind == "str":
                value = _strip_quotes(value)
            if section not in sections:
                sections[section] = dataclasses.asdict(getattr(self, section))
            sections[section][name] = value
        return Config(**{name: (cls(**sections[name]) if name in sections
                                else getattr(self, name))
                         for name, cls in _SECTIONS.items()})

    # ---- export -------------------------------------------------------------------------
    def to_dict(self) -> dict[str, dict[str, Any]]:
        """The configuration as nested plain values, ``{"rod": {"N": 5, ...}, ...}``.

        Returns
        -------
        dict
            Section name -> key -> value; ``Config.from_dict`` reads it back.
        """
        return {name: dataclasses.asdict(getattr(self, name)) for name in _SECTIONS}

    def flat(self) -> dict[str, Any]:
        """The configuration as dotted keys, ``{"rod.N": 5, "rod.kappa": 100.0, ...}``.

        Returns
        -------
        dict
            Dotted key -> value, every key of ``valid_keys()``.
        """
        return {f"{s}.{k}": v for s, d in self.to_dict().items() for k, v in d.items()}

    def to_toml(self) -> str:
        """The full resolved configuration as TOML (unset optional keys are commented).

        Returns
        -------
        str
            TOML text that ``from_toml_string`` reads back to an equal configuration.
        """
        lines = []
        for section, values in self.to_dict().items():
            lines.append(f"[{section}]")
            for key, value in values.items():
                if value is None:
                    lines.append(f"# {key} is unset")
                else:
                    lines.append(f"{key} = {_toml_value(value)}")
            lines.append("")
        return "\n".join(lines)

    def commented_toml(self) -> str:
        """``to_toml`` with each key preceded by a comment: meaning, unit, default, range
        (``rodjit config``).

        Returns
        -------
        str
            Valid TOML that ``from_toml_string`` reads back.
        """
        lines = []
        for section, values in self.to_dict().items():
            defaults = dataclasses.asdict(_SECTIONS[section]())
            lines.append(f"[{section}]")
            for key, value in values.items():
                lines.append(f"# {_FIELDS[section][key].comment(defaults[key])}")
                lines.append(f"# {key} is unset" if value is None else
                             f"{key} = {_toml_value(value)}")
            lines.append("")
        return "\n".join(lines)

    def get(self, key: str) -> Any:
        """The value of one dotted key.

        Parameters
        ----------
        key : str
            A dotted key, e.g. ``"rod.mu"``.

        Returns
        -------
        object
            Its value (None for an unset optional key).
        """
        section, name = key.split(".", 1)
        return getattr(getattr(self, section), name)

    # ---- display ------------------------------------------------------------------------
    def _overview(self) -> tuple[str, list[tuple[str, str]]]:
        title = (f"rodjit.Config: N = {self.rod.N}, mu = {self.rod.mu:g}, "
                 f"{self.time.integrator}, t_end = {self.time.t_end:g}")
        rows = [(name, ", ".join(f"{k} = {v}" for k, v in dataclasses.asdict(
                    getattr(self, name)).items() if v is not None)) for name in _SECTIONS]
        return title, rows

    def __repr__(self) -> str:
        from ._display import text
        return text(*self._overview())

    def _repr_html_(self) -> str:
        from ._display import html_table
        return html_table(*self._overview())


_TOML_HEADER = re.compile(r"""^\s*\[\s*(["']?)([^\]"']+)\1\s*\]""")
_TOML_KEY = re.compile(r"""^\s*([A-Za-z0-9_\-."' ]+?)\s*=""")


def _toml_line(text: str, key: str) -> int | None:
    """The line (from 1) of the TOML ``text`` that sets the dotted ``key``, or that opens
    the section ``key`` names when it ends with a dot (``"flor."``); None if no line
    does (a key checked against another, or set in an inline table)."""
    section, _, name = key.partition(".")
    current = ""
    for number, line in enumerate(text.splitlines(), 1):
        m = _TOML_HEADER.match(line)
        if m:
            current = m.group(2).strip()
            if not name and current == section:
                return number
            continue
        m = _TOML_KEY.match(line)
        if m:
            written = "".join(m.group(1).replace('"', "").replace("'", "").split())
            full = f"{current}.{written}" if current else written
            if full == key or (not name and full.startswith(section + ".")):
                return number
    return None


def _flatten(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in data.items():
        full = f"{prefix}{key}"
        if isinstance(value, Mapping):
            if prefix and full in valid_keys():   # a table where a value belongs
                raise ValueError(f"{full} takes a value ({field_spec(full).describe()}), "
                                 f"not a table ({{{', '.join(map(str, value))}}})")
            if prefix:  # sections nest one level only
                raise _unknown_key_error(full)
            if full not in _FIELDS:
                raise _unknown_section_error(full)
            out.update(_flatten(value, full + "."))
        else:
            out[full] = value
    return out


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)  # shortest round-trip form; finite by validation
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    raise TypeError(f"cannot write {value!r} as TOML")


def _strip_quotes(text: str) -> str:
    text = text.strip()
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
        return text[1:-1]
    return text


def parse_value(key: str, text: str) -> Any:
    """Parse a command-line value in TOML syntax; ``none`` unsets an optional key.

    Parameters
    ----------
    key : str
        The dotted key the value is for (its field checks the result).
    text : str
        The value as typed, e.g. ``"1e-3"`` or ``"'verlet'"``.

    Returns
    -------
    object
        The parsed value; None for ``none``/``null``/``unset``; text that is not a TOML
        value is returned as is, for the field's check to reject with its range.
    """
    text = text.strip()
    if text.lower() in ("none", "null", "unset"):
        return None
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text  # left to the field's own check, which names the key and range
