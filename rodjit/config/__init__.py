"""Validated, frozen run configuration, loadable from TOML and overridable by dotted keys.

The package, by job:

- ``keys``: the key specification, every key declared once with its type, allowed range,
  meaning and unit (``FIELDS``): one source for the error messages, ``rodjit config``
  (``commented_toml``, ``key_lines``), the file attributes and the documentation;
- ``sections``: the six frozen section dataclasses (``[rod]``, ...) and their defaults;
- ``checks``: what a configuration checks across keys, what a run refuses, what it warns;
- ``toml``: reading and writing TOML (files, text, comments, the line that set a key);
- ``core``: ``Config`` itself;
- ``errors``: ``ConfigError`` (carrying its key), ``MissingFile``, ``ModelWarning``.

Every name importable from ``rodjit.config`` before it became a package still is.
"""
from __future__ import annotations

from .checks import (CROSS_CHECKS, RUN_CHECKS, SHOCK_WARNING, VERLET_MU_MAX, VERLET_WARNING,
                     viscous_warning)
from .core import STORED_DEFAULTS, Config
from .errors import ConfigError, MissingFile, ModelWarning
from .keys import (COMPRESSIONS, CONTROLS, FIELDS, INTEGRATORS, KeySpec, field_spec,
                   key_lines, number_with_unit, parse_value, valid_keys)
from .sections import (SECTIONS, FloorConfig, GravityConfig, InitialConfig, OutputConfig,
                       RodConfig, TimeConfig)

__all__ = ["Config", "RodConfig", "FloorConfig", "GravityConfig", "InitialConfig",
           "TimeConfig", "OutputConfig", "INTEGRATORS", "CONTROLS", "ModelWarning",
           "MissingFile", "valid_keys", "field_spec", "key_lines", "parse_value",
           "CROSS_CHECKS", "RUN_CHECKS", "ConfigError", "KeySpec", "FIELDS", "SECTIONS",
           "COMPRESSIONS", "STORED_DEFAULTS", "SHOCK_WARNING", "VERLET_MU_MAX",
           "VERLET_WARNING", "number_with_unit", "viscous_warning"]

# The names these had when the configuration was one module (docs/hooks/generate.py and
# older scripts read them); aliases, not copies.
_FIELDS = FIELDS
_SECTIONS = SECTIONS
_Spec = KeySpec
