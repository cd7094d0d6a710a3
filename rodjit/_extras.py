"""Optional dependencies, imported on demand: a missing one raises one line that names the
extra to install."""
from __future__ import annotations

import importlib

__all__ = ["MissingExtra", "need"]


class MissingExtra(ImportError):
    """An optional dependency is not installed; the message says which extra brings it."""


def need(module: str, extra: str, what: str):
    """Import ``module`` (e.g. "xarray") for ``what`` (e.g. "Result.to_xarray"), or raise
    MissingExtra naming ``pip install 'rodjit[extra]'``."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingExtra(f"{what} needs {module.split('.')[0]}; install it with: "
                           f"pip install 'rodjit[{extra}]'") from None
