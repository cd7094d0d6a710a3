"""Compiled building blocks: forces, energies, banded solves (no time stepping here)."""

from .. import _lazy

# ``rodjit.kernels.NAME`` imports that submodule on first use (``rodjit._lazy``)
__getattr__ = _lazy.submodules(__name__)
