"""A rod law whose set-up kills its own process with SIGKILL when rod.kappa = 13: a point
that crashes its worker as hard as a segfault in user code would (used in workers only).
Otherwise it is the law of tests/custom_law.py, f(ε) = κ ε/(1+ε)."""
import os
import signal
from typing import NamedTuple

from custom_law import deriv, lower, primitive, value
from rodjit.laws import Law, register


class KillRod(NamedTuple):
    kappa: float


def _params(rod):
    if rod.kappa == 13.0:
        os.kill(os.getpid(), signal.SIGKILL)
    return KillRod(float(rod.kappa))


LAW = register(Law(name="kill-test", kind="rod", params=KillRod, from_config=_params,
                   value=value, deriv=deriv, primitive=primitive, lower=lower))
