"""Stress laws, the public way to add one: ``Law``, ``register`` and ``law_kernel``.

A law is a singular stress with its derivative and primitive (MODEL.md §1); its
parameters are a NamedTuple, its four functions are compiled with ``law_kernel`` (the
Numba options of every rodjit kernel, see ``rodjit._jit``: so a law must not allocate), and
``register`` makes it selectable as ``rod.law`` / ``floor.law``::

    import math
    from typing import NamedTuple
    from rodjit.laws import Law, law_kernel, register

    class LnRod(NamedTuple):            # f(ε) = κ ln(1 + ε), singular as ε ↓ −1
        kappa: float

    @law_kernel
    def ln_stress(e, p):
        return p.kappa * math.log1p(e)

    @law_kernel
    def ln_slope(e, p):
        return p.kappa / (1.0 + e)

    @law_kernel
    def ln_energy(e, p):                # zero at e = 0
        return p.kappa * ((1.0 + e) * math.log1p(e) - e)

    @law_kernel
    def ln_lower(p):
        return -1.0

    register(Law(name="ln", kind="rod", params=LnRod,
                 from_config=lambda rod: LnRod(float(rod.kappa)), value=ln_stress,
                 deriv=ln_slope, primitive=ln_energy, lower=ln_lower))

``Law`` documents the two optional shortcuts (``deriv_max``, ``difference``) and, for a floor
law, the optional continuation of its contact branch past 0 (``extension``,
``extension_deriv``) with which the embedded pairs step each side of the switch smoothly.
"""
from ._jit import kernel as law_kernel
from .model.laws import (AikiKosugiFloor, AikiKosugiRod, Law, deriv, get_law, law_names, law_of,
                         lower, primitive, register, value)

__all__ = ["Law", "register", "law_kernel", "get_law", "law_names", "law_of",
           "value", "deriv", "primitive", "lower", "AikiKosugiRod", "AikiKosugiFloor"]
