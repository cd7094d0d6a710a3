"""The namespace through which compiled-code caches name law parameter types.

Numba's on-disk cache index pickles the types of every signature it has compiled, so it
names each law's parameter class by module and qualified name.  ``register`` moves every
parameter class here; a process that lacks a law some earlier process registered (a user's
script, a test module) then unpickles a placeholder class instead of failing to import it,
and the foreign entry is just a cache miss.
"""
from ..._cache_names import placeholder_getattr

__getattr__ = placeholder_getattr(__name__, "an unregistered law")
