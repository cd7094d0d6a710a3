"""Reading and writing configurations as TOML: files and text in, (commented) text out,
and the line of a file that set a key (for its error message).

This module knows TOML and the key specification (``keys``), not the section classes:
``core.Config`` passes it plain nested dicts.
"""
from __future__ import annotations

import re
import tomllib
from pathlib import Path
from typing import Any, Mapping

from .errors import ConfigError, MissingFile
from .keys import FIELDS, KeySpec, field_spec, unknown_key_error, unknown_section_error, \
    valid_keys

__all__ = ["toml_value", "key_comment", "to_toml", "commented_toml", "toml_line", "flatten",
           "loads", "read_file", "with_file_and_line"]


def toml_value(value: Any) -> str:
    """``value`` (bool, int, finite float, str, or a tuple of them) as a TOML value.

    Raises
    ------
    TypeError
        Any other type.
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)  # shortest round-trip form; finite by validation
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, tuple):
        return "[" + ", ".join(toml_value(x) for x in value) + "]"
    raise TypeError(f"cannot write {value!r} as TOML")


def key_comment(spec: KeySpec, default: Any) -> str:
    """One comment line of ``rodjit config``: meaning, unit, default and allowed values."""
    shown = "unset" if default is None else toml_value(default)
    return f"{spec.meaning}{spec.unit_words()}; default {shown}; {spec.describe()}"


def to_toml(values: Mapping[str, Mapping[str, Any]]) -> str:
    """Nested values (section -> key -> value) as TOML; unset keys are comments."""
    lines = []
    for section, keys in values.items():
        lines.append(f"[{section}]")
        for key, value in keys.items():
            lines.append(f"# {key} is unset" if value is None else
                         f"{key} = {toml_value(value)}")
        lines.append("")
    return "\n".join(lines)


def commented_toml(values: Mapping[str, Mapping[str, Any]],
                   defaults: Mapping[str, Mapping[str, Any]]) -> str:
    """``to_toml`` with each key preceded by ``key_comment`` (its default from
    ``defaults``)."""
    lines = []
    for section, keys in values.items():
        lines.append(f"[{section}]")
        for key, value in keys.items():
            lines.append(f"# {key_comment(FIELDS[section][key], defaults[section][key])}")
            lines.append(f"# {key} is unset" if value is None else
                         f"{key} = {toml_value(value)}")
        lines.append("")
    return "\n".join(lines)


_TOML_HEADER = re.compile(r"""^\s*\[\s*(["']?)([^\]"']+)\1\s*\]""")
_TOML_KEY = re.compile(r"""^\s*([A-Za-z0-9_\-."' ]+?)\s*=""")


def toml_line(text: str, key: str) -> int | None:
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


def flatten(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested and/or dotted keys as dotted keys; sections nest one level only.

    Raises
    ------
    ConfigError
        An unknown section or key, or a table where a value belongs.
    """
    out: dict[str, Any] = {}
    for key, value in data.items():
        full = f"{prefix}{key}"
        if isinstance(value, Mapping):
            if prefix and full in valid_keys():   # a table where a value belongs
                raise ConfigError(f"{full} takes a value ({field_spec(full).describe()}), "
                                  f"not a table ({{{', '.join(map(str, value))}}})", full)
            if prefix:  # sections nest one level only
                raise unknown_key_error(full)
            if full not in FIELDS:
                raise unknown_section_error(full)
            out.update(flatten(value, full + "."))
        else:
            out[full] = value
    return out


def loads(text: str) -> dict[str, Any]:
    """TOML text as dotted keys.

    Raises
    ------
    ConfigError
        The text is not TOML, or names an unknown section or key.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"configuration is not valid TOML: {exc}") from None
    return flatten(data)


def read_file(path: str | Path) -> tuple[dict[str, Any], str]:
    """A TOML configuration file's raw keys (nested, as TOML gives them) and its text.

    Raises
    ------
    MissingFile
        The file does not exist.
    ConfigError
        It is a directory, unreadable, not text or not TOML (naming the file).
    """
    path = Path(path)
    where = f"configuration file {str(path)!r}"
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
        text = raw.decode("utf-8")
        return tomllib.loads(text), text
    except FileNotFoundError:
        raise MissingFile(path, "configuration file ") from None
    except IsADirectoryError:
        raise ConfigError(f"{where} is a directory") from None
    except PermissionError:
        raise ConfigError(f"{where} is not readable") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where} is not valid TOML: {exc}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{where} is not a text file") from None


def with_file_and_line(exc: ValueError, path: str | Path, text: str) -> ConfigError:
    """``exc`` prefixed with the file and, when its key is set on a line, that line."""
    key = getattr(exc, "key", None)
    line = toml_line(text, key) if key else None
    where = f"{str(path)}, line {line}" if line else str(path)
    return ConfigError(f"{where}: {exc}", key)
