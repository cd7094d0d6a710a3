"""Names of a package loaded on first use (PEP 562 ``__getattr__``): importing a package
costs almost nothing, and each name costs its own module's import when first read.  A
sweep's every worker process and every command-line verb import rodjit, and most need a
small part of it (a worker that runs batches never loads the plotting, analysis or
run-file modules).  ``rodjit`` and ``rodjit.sweeps`` load their public names so, and
``rodjit``'s subpackages (``rodjit.analysis``) too; a subpackage's own submodules are
imported by name (``import rodjit.output.hdf5``)."""
from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["attribute", "public_names"]


def attribute(package: str, where: Mapping[str, str], name: str) -> Any:
    """``package``'s attribute ``name``: the object of that name in the module
    ``where[name]`` (relative to ``package``; a module itself if it is named after the
    name), else the subpackage or submodule ``package.name``, imported; AttributeError if
    there is none.  The value is stored on the package, so each name is looked up once."""
    if name in where:
        module = importlib.import_module(where[name], package)
        value = module if module.__name__ == f"{package}.{name}" else getattr(module, name)
    else:
        if name.startswith("__"):      # probes such as __wrapped__ are no submodules
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        try:
            value = importlib.import_module(f"{package}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{package}.{name}":
                raise            # the submodule exists and fails to import: say why
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
    setattr(sys.modules[package], name, value)
    return value


def public_names(package: str, where: Mapping[str, str]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for the package ``package`` whose public names live
    in the modules ``where`` says (``attribute``); ``dir()`` lists them before first use."""
    def __getattr__(name: str) -> Any:
        return attribute(package, where, name)

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(where))

    return __getattr__, __dir__
