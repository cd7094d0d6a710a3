"""Named configurations shipped in ``data/`` (installed as ``rodjit.data``)."""
from __future__ import annotations

from importlib import resources
from importlib.resources.abc import Traversable
from pathlib import Path

from .config import Config

__all__ = ["preset_names", "preset_path", "load_preset"]


def _files() -> dict[str, Traversable]:
    """Preset files from the installed package data, or from data/ in a source tree."""
    try:
        root = resources.files("rodjit.data")
        found: dict[str, Traversable] = {p.name: p for p in root.iterdir()
                                         if p.name.endswith(".toml")}
        if found:
            return found
    except (ModuleNotFoundError, FileNotFoundError):
        pass
    root = Path(__file__).resolve().parent.parent / "data"
    return {p.name: p for p in sorted(root.glob("*.toml"))}


def preset_names() -> list[str]:
    """Preset names: file stems with '_' written as '-' (``paper-mu0``, ``paper-mu100``)."""
    return sorted(name[:-5].replace("_", "-") for name in _files())


def preset_path(name: str) -> Traversable:
    """The TOML file of preset ``name`` (in the installed package data).

    Parameters
    ----------
    name : str
        A name of ``preset_names()``, e.g. ``"paper-mu100"``.

    Returns
    -------
    importlib.resources.abc.Traversable or pathlib.Path
        The file; ``Config.from_toml_string(path.read_text())`` reads it.

    Raises
    ------
    ValueError
        An unknown preset, naming the available ones.
    """
    files = _files()
    key = name.replace("-", "_") + ".toml"
    if key not in files:
        raise ValueError(f"unknown preset {name!r}; available presets: {', '.join(preset_names())}")
    return files[key]


def load_preset(name: str) -> Config:
    """The shipped configuration ``name`` (``data/<name>.toml``).

    Parameters
    ----------
    name : str
        One of ``preset_names()`` (``paper-mu0``, ``paper-mu100``, ...).

    Returns
    -------
    Config
        The preset's configuration, defaults filled in.

    Raises
    ------
    ValueError
        ``name`` is not a preset (the message lists the presets).
    """
    return Config.from_toml_string(preset_path(name).read_text())
