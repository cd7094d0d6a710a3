"""Placeholder classes for a cache namespace (``model.laws.registered``,
``stepping.registered``).

Numba's on-disk cache index pickles the types of the signatures it compiled, naming each
parameter class by module and qualified name.  A namespace module that registered classes
are moved into answers an unknown name with a placeholder class (made once per name), so a
process lacking a class some earlier process registered unpickles the placeholder instead
of failing to import it, and the foreign cache entry is just a miss.
"""
from __future__ import annotations

from typing import Callable

__all__ = ["placeholder_getattr"]


def placeholder_getattr(module: str, what: str) -> Callable[[str], type]:
    """The module-level ``__getattr__`` (PEP 562) of the namespace ``module``: a name it
    lacks is a placeholder tuple class documented as ``what``."""
    made: dict[str, type] = {}

    def __getattr__(name: str) -> type:
        if name.startswith("__"):
            raise AttributeError(name)
        if name not in made:
            made[name] = type(name, (tuple,), {"__module__": module, "__doc__": what})
        return made[name]

    return __getattr__
