"""The key specification: every configuration key declared once, with its type, allowed
range, meaning and unit (``FIELDS``).

One source for the error messages, ``rodjit config`` (its comments and ``--keys``), the
files' attributes, the section classes' documentation and the configuration reference
(docs/hooks/generate.py).  Defaults are the section dataclasses' (``sections``).
"""
from __future__ import annotations

import difflib
import math
import numbers
import re
import tomllib
from typing import Any, Callable

from ..stepping.registry import NAMES as INTEGRATORS   # the one list of integrator names
from .errors import ConfigError

__all__ = ["KeySpec", "FIELDS", "INTEGRATORS", "CONTROLS", "COMPRESSIONS", "field_spec",
           "valid_keys", "key_lines", "parse_value", "number_with_unit", "unknown_key_error",
           "unknown_section_error", "strip_quotes"]

# time.control of the kick–drift–kick integrators: "tolerance" (steps from time.rtol and
# time.atol, stability as a cap) or "cfl" (time.cfl × the stability limit, no estimate)
CONTROLS = ("tolerance", "cfl")
COMPRESSIONS = ("gzip", "lzf", "none")


def registered_integrators() -> tuple[str, ...]:
    """The values ``time.integrator`` takes: ``"auto"`` (the registry's choice per study,
    ``registry.AUTO_TABLE``) and the integrators registered now (``registry.register``
    adds to the built-in ones)."""
    from ..stepping import registry
    return (registry.AUTO,) + registry.NAMES


class KeySpec:
    """Type, range, meaning and unit of one configuration key; ``coerce`` checks a value.

    Parameters
    ----------
    kind : str
        ``"int"``, ``"float"``, ``"str"``, ``"bool"`` or ``"times"`` (a list of
        increasing times, a tuple of floats).
    rng : str, optional
        The allowed range, as messages print it (``"> 0"``).
    check : callable, optional
        ``check(value) -> bool``: whether a value of the right kind is in range.
    optional : bool, optional
        Whether the key may be unset (None).
    choices : tuple of str, or a callable giving one, optional
        The allowed values of a text key (a callable: a registry answering at call time).
    meaning : str
        What the key sets: for comments, listings, documentation and file attributes.
    unit : str, optional
        UDUNITS string (docs/MODEL.md "Units"); ``"1"`` dimensionless, ``""`` for text
        and boolean keys.
    """

    def __init__(self, kind: str, rng: str = "", check: Callable[[Any], bool] | None = None,
                 optional: bool = False,
                 choices: tuple[str, ...] | Callable[[], tuple[str, ...]] | None = None, *,
                 meaning: str, unit: str = "") -> None:
        self.kind, self.rng, self.check, self.optional = kind, rng, check, optional
        self._choices = choices
        self.meaning = meaning
        self.unit = unit

    @property
    def choices(self) -> tuple[str, ...] | None:
        """The allowed values (None: any of the kind); registries answer at call time."""
        return self._choices() if callable(self._choices) else self._choices

    def coerce(self, key: str, value: Any) -> Any:
        """``value`` checked and converted to the field's Python type (NumPy integers and
        floats as int and float; booleans, NumPy's included, are not numbers here).

        Parameters
        ----------
        key : str
            The dotted key, for the message.
        value : object
            The value as given (a string only for text keys).

        Returns
        -------
        object
            The value as the field's Python type (None for an unset optional key).

        Raises
        ------
        ConfigError
            The value is of the wrong kind or out of range (``key`` set).
        """
        if value is None:
            if self.optional:
                return None
            raise ConfigError(f"{key} must be set ({self.describe()})", key)
        if self.kind == "times":
            return self._times(key, value)
        if isinstance(value, str) and self.kind != "str":
            raise ConfigError(_quoted_error(key, value, self), key)
        is_bool = isinstance(value, bool) or type(value).__name__ in ("bool_", "bool")
        if self.kind == "bool":
            if not is_bool:
                raise ConfigError(f"{key} = {value!r} is not a boolean ({self.describe()})",
                                  key)
            value = bool(value)
        elif self.kind == "int":
            if is_bool or not isinstance(value, numbers.Real):
                raise ConfigError(f"{key} = {value!r} is not an integer ({self.describe()})",
                                  key)
            if isinstance(value, numbers.Integral):
                value = int(value)
            elif float(value).is_integer():
                value = int(float(value))
            else:
                raise ConfigError(f"{key} = {value!r} is not an integer ({self.describe()})",
                                  key)
        elif self.kind == "float":
            if is_bool or not isinstance(value, numbers.Real):
                raise ConfigError(f"{key} = {value!r} is not a number ({self.describe()})",
                                  key)
            try:
                value = float(value)
            except OverflowError:      # an integer beyond any float (hundreds of digits)
                raise ConfigError(f"{key} = {shown(value)} is out of range "
                                  f"({self.describe()})", key) from None
            if not math.isfinite(value):
                raise ConfigError(f"{key} = {value!r} is not finite ({self.describe()})", key)
        elif self.kind == "str":
            if not isinstance(value, str):
                raise ConfigError(f"{key} = {value!r} is not a string ({self.describe()})",
                                  key)
            if self.choices is not None and value not in self.choices:
                raise ConfigError(f"{key} = {value!r} is not allowed ({self.describe()})",
                                  key)
        if self.check is not None and not self.check(value):
            raise ConfigError(f"{key} = {shown(value)} is out of range ({self.describe()})",
                              key)
        return value

    def _times(self, key: str, value: Any) -> tuple[float, ...]:
        """A list of times: a sequence of numbers (a TOML array, a list, a NumPy array) or
        their text separated by commas, as a tuple of floats; ``check`` its order."""
        if isinstance(value, str):
            text = value.strip().strip("[]")
            try:
                value = [float(x) for x in text.split(",") if x.strip()]
            except ValueError:
                raise ConfigError(f"{key} = {value!r} is not a list of numbers "
                                  f"({self.describe()})", key) from None
        if hasattr(value, "tolist"):                 # a NumPy array or scalar
            value = value.tolist()
        if not isinstance(value, (list, tuple)):
            raise ConfigError(f"{key} = {value!r} is not a list of numbers "
                              f"({self.describe()})", key)
        out: list[float] = []
        for i, x in enumerate(value):
            if isinstance(x, bool) or not isinstance(x, numbers.Real):
                raise ConfigError(f"{key}[{i}] = {x!r} is not a number ({self.describe()})",
                                  key)
            x = float(x)
            if not math.isfinite(x) or x < 0.0:
                raise ConfigError(f"{key}[{i}] = {x!r} is out of range ({self.describe()})",
                                  key)
            if out and not x > out[-1]:
                raise ConfigError(f"{key}[{i}] = {x!r} is out of range: not after "
                                  f"{key}[{i - 1}] = {out[-1]!r} ({self.describe()})", key)
            out.append(x)
        return tuple(out)

    def describe(self) -> str:
        """The allowed values in words (``"float > 0"``, ``"one of 'gzip', ..."``)."""
        if self.choices is not None:
            text = "one of " + ", ".join(repr(c) for c in self.choices)
        elif self.kind == "bool":
            text = "true or false"
        else:
            kind = "list of times" if self.kind == "times" else self.kind
            text = f"{kind} {self.rng}".strip()
        return text + (", or unset" if self.optional else "")

    def unit_words(self) -> str:
        """The unit as a comment gives it: ``"; unit N s"``, ``"; dimensionless"`` or
        ``""``."""
        if self.unit == "1":
            return "; dimensionless"
        return f"; unit {self.unit}" if self.unit else ""


def shown(value: Any) -> str:
    """``repr(value)``, an integer of many digits shortened (its digits counted)."""
    text = repr(value)
    if isinstance(value, int) and len(text) > 24:
        return f"{text[:12]}...({len(text.lstrip('-'))} digits)"
    return text


def _quoted_error(key: str, value: str, spec: KeySpec) -> str:
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


def _pos(x: float) -> bool:
    return x > 0


def _nonneg(x: float) -> bool:
    return x >= 0


FIELDS: dict[str, dict[str, KeySpec]] = {
    "rod": {
        "N": KeySpec("int", "in [1, 10000000]", lambda n: 1 <= n <= 10_000_000,
                     meaning="number of rod segments (N + 1 nodes)", unit="1"),
        "kappa": KeySpec("float", "> 0", _pos, meaning="elastic modulus kappa of the rod",
                         unit="N"),
        "gamma": KeySpec("float", ">= 0", _nonneg,
                         meaning="bending (beam regularisation) coefficient gamma",
                         unit="N m2"),
        "mu": KeySpec("float", ">= 0", _nonneg, meaning="viscosity mu of the rod", unit="N s"),
        "law": KeySpec("str", "a registered rod law", meaning="stress law f of the rod"),
    },
    "floor": {
        "kappa_b": KeySpec("float", "> 0", _pos, meaning="stiffness kappa_b of the floor",
                           unit="N"),
        "beta": KeySpec("float", "> 0", _pos, unit="m",
                        meaning="bending limit beta of the floor (its stress is singular at "
                                "u_0 = -beta; a thin layer: beta >= 1, the rod's length, "
                                "warns)"),
        "law": KeySpec("str", "a registered floor law",
                       meaning="stress law sigma_b of the floor"),
        "damping": KeySpec("float", ">= 0 (0: none)", _nonneg, unit="s m-1",
                           meaning="Hunt-Crossley damping alpha of the floor: its force is "
                                   "sigma_b(u_0) max(0, 1 - alpha v_0), alpha times the "
                                   "penetration rate"),
    },
    "gravity": {
        "g": KeySpec("float", "finite, signed along +u (negative pulls down)",
                     meaning="gravitational acceleration along +u (g > 0 that never brings "
                             "the rod down to the floor warns: no impact)", unit="m s-2"),
    },
    "initial": {
        "height": KeySpec("float", "> -floor.beta",
                          meaning="initial height of the bottom end u_0", unit="m"),
        "velocity": KeySpec("float", "finite", meaning="initial velocity of every node",
                            unit="m s-1"),
        "strain": KeySpec("float", "> -1", lambda e: e > -1.0,
                          meaning="initial uniform strain of the rod", unit="1"),
        "impact_speed": KeySpec("float", "> 0 (unset: initial.velocity)", _pos,
                                optional=True, unit="m s-1",
                                meaning="speed at which the bottom reaches the floor: the "
                                        "rod starts at initial.height with the uniform "
                                        "velocity a free fall needs for it (instead of "
                                        "initial.velocity)"),
    },
    "time": {
        "t_end": KeySpec("float", "> 0", _pos, meaning="time at which the run ends", unit="s"),
        "integrator": KeySpec("str", choices=registered_integrators,
                              meaning="time integrator; 'auto' picks the fastest for the "
                                      "regime (rod.mu, rod.gamma, rod.N) once per study"),
        "cfl": KeySpec("float", "in (0, 1]", lambda c: 0 < c <= 1, unit="1",
                       meaning="fraction of the stability limit taken as the step (verlet, "
                               "semi-implicit with time.control = 'cfl')"),
        "control": KeySpec("str", choices=CONTROLS,
                           meaning="step control of verlet and semi-implicit: 'tolerance' "
                                   "(steps from rtol and atol, stability as a cap) or 'cfl' "
                                   "(time.cfl times the stability limit)"),
        "dt_max": KeySpec("float", "> 0", _pos, optional=True,
                          meaning="largest adaptive step", unit="s"),
        "dt_min": KeySpec("float", "> 0", _pos, meaning="smallest step before the run fails",
                          unit="s"),
        "dt": KeySpec("float", "> 0 (fixed step; unset for adaptive steps)", _pos,
                      optional=True, meaning="fixed time step", unit="s"),
        "rtol": KeySpec("float", "in (0, 1)", lambda r: 0 < r < 1, unit="1",
                        meaning="relative tolerance of the local error per step (every "
                                "integrator under time.control = 'tolerance')"),
        "atol": KeySpec("float", "> 0", _pos, unit="m",
                        meaning="absolute tolerance of the local error per step (heights "
                                "u)"),
        "stop_after_bounces": KeySpec("int", ">= 0 (0: off)", lambda k: k >= 0, unit="1",
                                      meaning="end the run once this many bounces are "
                                              "over (at the apex of the flight after the "
                                              "last), before time.t_end"),
        "stop_at_rest": KeySpec("bool",
                                meaning="end the run once the rod can never leave the floor "
                                        "again (its energy below the lift-off energy; "
                                        "needs gravity.g < 0), before time.t_end"),
    },
    "output": {
        "snapshot_interval": KeySpec("float", ">= 0 (0 disables snapshots)", _nonneg,
                                     unit="s",
                                     meaning="simulated time between snapshots of u and v"),
        "diagnostics_interval": KeySpec("float", ">= 0 (0 disables diagnostics)", _nonneg,
                                        unit="s", meaning="simulated time between "
                                                          "diagnostics rows"),
        "times": KeySpec("times", "increasing, each >= 0; empty: off",
                         unit="s",
                         meaning="the times of the snapshots of u and v, in place of "
                                 "output.snapshot_interval's grid (solve_ivp's t_eval)"),
        "observer": KeySpec("str", "a registered observer ('none': off)",
                            meaning="compiled code watching every step, whose values are "
                                    "Result.observed and sweep columns "
                                    "(rodjit.observers)"),
        "compression": KeySpec("str", choices=COMPRESSIONS,
                               meaning="compression of the HDF5 tables"),
        "interpolate": KeySpec("bool",
                               meaning="outputs of dp54, dop853 and radau5 from the "
                                       "integrator's dense output between steps (true) or "
                                       "from steps landing on each output time (false)"),
    },
}


def field_spec(key: str) -> KeySpec:
    """The spec of a dotted key: its kind, range, meaning and unit.

    Parameters
    ----------
    key : str
        A dotted configuration key, e.g. ``"rod.mu"``.

    Returns
    -------
    KeySpec
        The field's specification (``kind``, ``describe()``, ``meaning``, ``unit``).

    Raises
    ------
    ConfigError
        For an unknown key, naming the closest valid key.
    """
    section, _, name = key.partition(".")
    try:
        return FIELDS[section][name]
    except KeyError:
        raise unknown_key_error(key) from None


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
    return [f"{s}.{k}" for s, fields in FIELDS.items() for k in fields]


def unknown_section_error(section: str) -> ConfigError:
    """The error for a section that does not exist, naming the closest one (its ``key``
    is ``"SECTION."``, for the line of a TOML file that opens it)."""
    close = difflib.get_close_matches(section, list(FIELDS), n=1, cutoff=0.5)
    hint = f"; did you mean [{close[0]}]?" if close else ""
    return ConfigError(f"unknown configuration section [{section}]{hint} sections: "
                       + ", ".join(f"[{name}]" for name in FIELDS), section + ".")


def unknown_key_error(key: str) -> ConfigError:
    """The error for a key that does not exist: the right name in the wrong section first,
    then the closest spelling, then every valid key."""
    keys = valid_keys()
    name = key.rsplit(".", 1)[-1]
    close = [k for k in keys if name and k.rsplit(".", 1)[1] == name][:1]
    close = close or difflib.get_close_matches(key, keys, n=1, cutoff=0.6)
    hint = f"; did you mean '{close[0]}'?" if close else ""
    return ConfigError(f"unknown configuration key '{key}'{hint} valid keys: "
                       f"{', '.join(keys)}", key)


def strip_quotes(text: str) -> str:
    """``text`` without one pair of surrounding quotes (``--set time.integrator='dp54'``)."""
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
