"""A rod law whose set-up kills its own process with SIGKILL when rod.kappa = 13: a point
that crashes its worker as hard as a segfault in user code would (used in workers only).
Otherwise it is a proper law: f(ε) = κ ε/(1+ε), as tests/custom_law.py."""
import math
import os
import signal
from typing import NamedTuple

from rodjit._jit import kernel
from rodjit.model.laws import Law, register


class KillRod(NamedTuple):
    kappa: float


@kernel
def value(e, p):
    return p.kappa * e / (1.0 + e)


@kernel
def deriv(e, p):
    return p.kappa / ((1.0 + e) * (1.0 + e))


@kernel
def primitive(e, p):
    return p.kappa * (e - math.log1p(e))


@kernel
def lower(p):
    return -1.0


def _params(rod):
    if rod.kappa == 13.0:
        os.kill(os.getpid(), signal.SIGKILL)
    return KillRod(float(rod.kappa))


LAW = register(Law(name="kill-test", kind="rod", params=KillRod, from_config=_params,
                   value=value, deriv=deriv, primitive=primitive, lower=lower))
