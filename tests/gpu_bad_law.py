"""A rod law the CPU compiles and CUDA does not (tests/test_gpu_ptx.py): f(ε) = κ ε, plus
0 × a NumPy random number, which numba-cuda cannot type."""
from typing import NamedTuple

import numpy as np

from rodjit.laws import Law, law_kernel, register


class NoisyRod(NamedTuple):
    kappa: float


@law_kernel
def value(e, p):
    return p.kappa * e + 0.0 * np.random.random()


@law_kernel
def deriv(e, p):
    return p.kappa


@law_kernel
def primitive(e, p):
    return 0.5 * p.kappa * e * e


@law_kernel
def lower(p):
    return -1.0


LAW = register(Law(name="gpu-bad-test", kind="rod", params=NoisyRod,
                   from_config=lambda rod: NoisyRod(float(rod.kappa)),
                   value=value, deriv=deriv, primitive=primitive, lower=lower))
