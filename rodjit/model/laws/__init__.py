"""Stress laws: the rod's f and the floor's σ_b, each with derivative and primitive.

Adding a law with the same singular structure is one module like ``aiki_kosugi.py``:
a NamedTuple of parameters, four functions compiled with ``rodjit.laws.law_kernel`` (two
more are optional shortcuts: ``deriv_max`` for the stiffness bound, ``difference`` for the
energy step's quotients) and a ``register(Law(...))`` call; import it here (or anywhere
before the run) and select it with ``rod.law`` / ``floor.law``.  No kernel changes.  Users
import all of this from the public ``rodjit.laws``.
"""

from .base import (Law, deriv, get_law, law_for_numba_type, law_names, law_of, lower,
                   max_deriv, primitive, register, value)
from . import aiki_kosugi
from .aiki_kosugi import AikiKosugiFloor, AikiKosugiRod

__all__ = [
    "Law", "register", "get_law", "law_names", "law_of", "law_for_numba_type",
    "value", "deriv", "primitive", "lower", "max_deriv",
    "AikiKosugiRod", "AikiKosugiFloor", "aiki_kosugi",
]
