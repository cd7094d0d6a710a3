"""The namespace through which compiled-code caches name the parameter types of integrators
and observers registered from outside (``registry.register``, ``observers.register``).

Numba's on-disk cache index pickles the types of every signature it has compiled, so it
names each scheme's parameter class by module and qualified name.  ``adopt`` moves a
registered scheme's parameter class here, under a name that identifies its implementation;
a process that lacks the scheme (a user's script, a test module) then unpickles a
placeholder class instead of failing to import it, and the foreign entry is just a cache
miss (as ``model.laws.registered`` does for laws).
"""
import hashlib

from .._cache_names import placeholder_getattr

def adopt(params: type, name: str, parts) -> str:
    """Name ``params`` (the parameter class of the integrator or observer ``name``, whose
    compiled functions are ``parts``) through this namespace, under an alias made of the
    name and a digest of the functions' code; returns the alias."""
    h = hashlib.sha1(f"{params.__module__}.{params.__qualname__}".encode())
    for part in parts:
        code = getattr(getattr(part, "py_func", part), "__code__", None)
        if code is not None:
            h.update(code.co_code)
            h.update(repr(code.co_consts).encode())
            h.update(repr(code.co_names).encode())
    alias = f"{''.join(c if c.isalnum() else '_' for c in name)}_{h.hexdigest()[:16]}"
    params.__module__ = __name__
    params.__qualname__ = alias
    globals()[alias] = params
    return alias


__getattr__ = placeholder_getattr(__name__, "an unregistered scheme")
