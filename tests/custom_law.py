"""A stress law written the way a user would add one: one small module, no kernel edits.

f(ε) = κ ε/(1+ε): singular as ε ↓ −1, f'(0) = κ, primitive κ(ε − log(1+ε)).
"""
import math
from typing import NamedTuple

from rodjit.laws import Law, law_kernel, register


class LogRod(NamedTuple):
    kappa: float


@law_kernel
def value(e, p):
    return p.kappa * e / (1.0 + e)


@law_kernel
def deriv(e, p):
    q = 1.0 + e
    return p.kappa / (q * q)


@law_kernel
def primitive(e, p):
    return p.kappa * (e - math.log1p(e))


@law_kernel
def lower(p):
    return -1.0


LAW = register(Law(name="log-test", kind="rod", params=LogRod,
                   from_config=lambda rod: LogRod(float(rod.kappa)),
                   value=value, deriv=deriv, primitive=primitive, lower=lower))


class RaiseRod(NamedTuple):
    kappa: float


def _raising_params(rod):
    if rod.kappa == 13.0:
        raise ValueError("this law refuses rod.kappa = 13")
    return RaiseRod(float(rod.kappa))


# the log law whose parameters cannot be made for rod.kappa = 13: a point that cannot start
RAISING = register(Law(name="raise-test", kind="rod", params=RaiseRod,
                       from_config=_raising_params, value=value, deriv=deriv,
                       primitive=primitive, lower=lower))
