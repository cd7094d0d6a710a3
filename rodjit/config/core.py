"""The run configuration: ``Config``, six checked sections, built from dicts, TOML files
and text, overridable by dotted keys, written back as TOML.

Numbers may be Python or NumPy numbers; a TOML file is strict (a quoted number is an
error), while ``override`` also takes strings in TOML syntax, as the command line's
``--set`` gives them.  Bad values raise ``ConfigError`` (a ValueError) naming the key and
the range, at the moment they enter.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from ..stepping.registry import AUTO, choose
from ..model.system import start_velocity
from .checks import CROSS_CHECKS, RUN_CHECKS, model_warnings, setup_warnings, times_warnings
from .errors import ConfigError
from .keys import FIELDS, parse_value, strip_quotes, unknown_key_error
from .sections import (SECTIONS, FloorConfig, GravityConfig, InitialConfig, OutputConfig,
                       RodConfig, TimeConfig)
from .toml import commented_toml, flatten, loads, read_file, to_toml, with_file_and_line

__all__ = ["Config", "STORED_DEFAULTS"]

# keys that a stored configuration may lack (written before they existed), with the value
# that reproduces what such a run did
STORED_DEFAULTS = {"time.control": "cfl", "output.interpolate": False}


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
    choice : str
        How ``time.integrator`` was chosen where the user asked for ``"auto"``
        (``resolve``): one line naming the row of the registry's table, "" otherwise.  Not
        a configuration key and not compared: it travels beside the configuration.

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
    # How ``time.integrator`` was chosen where the user asked for "auto" (``resolve``): one
    # line naming the row of the registry's table; "" otherwise.  Not a key: it travels
    # beside the configuration (the summary, ``rodjit info``, run and sweep files)
    choice: str = field(default="", compare=False, repr=False)

    def __post_init__(self) -> None:
        for name, cls in SECTIONS.items():
            if not isinstance(getattr(self, name), cls):
                raise ConfigError(f"{name} must be a {cls.__name__}")
        for keys, check in CROSS_CHECKS:
            check(*(self.get(key) for key in keys))

    # ---- construction -------------------------------------------------------------------
    def warnings(self) -> tuple[str, ...]:
        """What this configuration's results cannot be trusted for.

        Returns
        -------
        tuple of str
            One sentence per known limitation (empty: nothing known): the shock-forming
            μ = γ = 0 model, verlet at large μ; and per set-up that is valid but almost
            surely a mistake (``checks.setup_warnings``): a ``gravity.g > 0`` under which
            the rod never comes down to the floor (no impact), a ``floor.beta`` at least
            the rod's length, listed ``output.times`` after ``time.t_end``.
        """
        return (model_warnings(self.rod.mu, self.rod.gamma, self.resolve().time.integrator)
                + setup_warnings(self.gravity.g, self.initial.height,
                                 start_velocity(self.initial.height, self.initial.velocity,
                                                self.initial.impact_speed, self.gravity.g),
                                 self.floor.beta)
                + times_warnings(self.output.times, self.time.t_end))

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
        resolved = self.resolve()
        for keys, check in RUN_CHECKS:
            check(*(resolved.get(key) for key in keys))

    def chosen(self, choice: str) -> "Config":
        """This configuration with another record of how "auto" chose its integrator.

        Parameters
        ----------
        choice : str
            The record (``Config.choice``), as a file stores it beside the configuration.

        Returns
        -------
        Config
            ``self`` if it already holds ``choice``, else a copy that does.
        """
        return dataclasses.replace(self, choice=choice) if choice != self.choice else self

    def ran_with(self) -> str:
        """``time.integrator``, with how "auto" chose it (``choice``) where it did: the one
        wording of the summary, ``rodjit info`` and ``--dry-run``."""
        return (f"{self.time.integrator}, {self.choice}" if self.choice
                else self.time.integrator)

    def resolve(self) -> "Config":
        """The configuration a run takes: ``time.integrator = "auto"`` replaced by the
        integrator the registry's table picks for this rod (``registry.choose``: by rod.mu,
        rod.gamma and rod.N; on a conservative rod, μ = γ = 0, the tolerances divided by
        the run's length in seconds, so the energy stays within 1e-6 over long runs), with
        ``choice`` saying which row chose it; any other configuration as it is.

        A study resolves its base configuration once, so its points, rungs and trials (and
        a resume) keep one integrator: a ``rod.mu`` sweep from μ = 0 to 10 runs the
        integrator chosen at μ = 0 throughout.

        Returns
        -------
        Config
            ``self`` when ``time.integrator`` names an integrator, else a new configuration.

        Examples
        --------
        >>> Config().resolve().time.integrator
        'dop853'
        >>> Config().override({"rod.mu": 100.0}).resolve().time.integrator
        'radau5'
        """
        t = self.time
        if t.integrator != AUTO:
            return self
        name, rtol, atol, why = choose(self.rod.mu, self.rod.gamma, self.rod.N, t.t_end,
                                       t.rtol, t.atol)
        changes: dict[str, Any] = {"time.integrator": name}
        if rtol != t.rtol:
            changes.update({"time.rtol": rtol, "time.atol": atol})
        return self._replaced(changes, text=False).chosen(why)

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
        return cls().override(flatten(data))

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
        data, text = read_file(path)
        try:
            return cls()._replaced(flatten(data), text=False)
        except ValueError as exc:
            raise with_file_and_line(exc, path, text) from None

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
        return cls()._replaced(loads(text), text=False)

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
        flat = loads(text)
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
        TypeError
            ``changes`` is not a mapping (a ``"rod.mu=1"`` text, a list, None).
        """
        if not isinstance(changes, Mapping):
            raise TypeError(f"Config.override(changes): changes must be a mapping of dotted "
                            f"keys to values, e.g. {{'rod.mu': 100.0}}, not "
                            f"{_short(changes)} ({type(changes).__name__})")
        return self._replaced(changes, text=True)

    def _replaced(self, changes: Mapping[str, Any], *, text: bool) -> "Config":
        """``override``; ``text``: strings for non-text keys are parsed as TOML values (else
        they are an error naming the key, as in a TOML file)."""
        # only the sections a change touches are rebuilt (and checked again); the others
        # are the same frozen objects (a sweep builds one configuration per point)
        sections: dict[str, dict[str, Any]] = {}
        for key, value in changes.items():
            if not isinstance(key, str) or "." not in key:
                raise unknown_key_error(str(key))
            section, name = key.split(".", 1)
            if section not in FIELDS or name not in FIELDS[section]:
                raise unknown_key_error(key)
            if text and isinstance(value, str) and FIELDS[section][name].kind != "str":
                value = parse_value(key, value)
            elif text and isinstance(value, str) and FIELDS[section][name].kind == "str":
                value = strip_quotes(value)
            if section not in sections:
                sections[section] = dataclasses.asdict(getattr(self, section))
            sections[section][name] = value
        rebuilt: dict[str, Any] = {name: (cls(**sections[name]) if name in sections
                                          else getattr(self, name))
                                   for name, cls in SECTIONS.items()}
        # the choice of "auto" holds while the keys it set are the ones it chose
        keep = self.choice and not _CHOSEN_KEYS.intersection(changes)
        return Config(**rebuilt, choice=self.choice if keep else "")

    # ---- export -------------------------------------------------------------------------
    def to_dict(self) -> dict[str, dict[str, Any]]:
        """The configuration as nested plain values, ``{"rod": {"N": 5, ...}, ...}``.

        Returns
        -------
        dict
            Section name -> key -> value; ``Config.from_dict`` reads it back.
        """
        return {name: dataclasses.asdict(getattr(self, name)) for name in SECTIONS}

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
        return to_toml(self.to_dict())

    def commented_toml(self) -> str:
        """``to_toml`` with each key preceded by a comment: meaning, unit, default, range
        (``rodjit config``).

        Returns
        -------
        str
            Valid TOML that ``from_toml_string`` reads back.
        """
        return commented_toml(self.to_dict(), Config().to_dict())

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
                    getattr(self, name)).items() if v is not None)) for name in SECTIONS]
        return title, rows

    def __repr__(self) -> str:
        from .._display import text
        return text(*self._overview())

    def _repr_html_(self) -> str:
        from .._display import html_table
        return html_table(*self._overview())


_CHOSEN_KEYS = frozenset({"time.integrator", "time.rtol", "time.atol"})


def _short(value: Any) -> str:
    """``repr(value)``, cut to a message's length."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
