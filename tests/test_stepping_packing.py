"""The packing of a point's parameter tuples into one row of doubles (``stepping.packing``):
every field of every integrator's real tuples comes back exactly, in Python, from the same
source the compiled callers use."""
from __future__ import annotations

import math
import struct
from typing import NamedTuple

import numpy as np
import pytest

import rodjit
from rodjit.driver.setup import parameters
from rodjit.stepping import packing as P
from rodjit.stepping.registry import NAMES


def _params(integrator: str) -> tuple:
    return parameters(rodjit.Config().override({"time.integrator": integrator}))


def _same(a, b) -> bool:
    """Equal to the bit and of the same type (a float's sign of zero and NaN included)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, float):
        return struct.pack("<d", a) == struct.pack("<d", b)
    return a == b


def _assert_round_trip(params):
    row = P.pack(params)
    assert all(type(x) is float for x in row)
    # the Python version, from an array row as the compiled callers get it
    back = P.rebuild(params, np.array(row, dtype=np.float64))
    # the generated source itself, on the row as Python floats
    names = [f"C{k}" for k in range(len(params))]
    ns = {n: type(t) for n, t in zip(names, params)}
    source = P.rebuild_source(P.kinds(params), "row", names)
    from_source = tuple(eval(x, ns, {"row": row}) for x in source)
    for got in (back, from_source):
        assert len(got) == len(params)
        for a, b in zip(got, params):
            assert type(a) is type(b)
            for field, x, y in zip(b._fields, a, b):
                assert _same(x, y), (type(b).__name__, field, x, y)


@pytest.mark.parametrize("integrator", sorted(NAMES))
def test_every_field_of_every_integrators_tuples_comes_back_exactly(integrator):
    params = _params(integrator)
    ks = P.kinds(params, exact=True)
    assert set("".join(ks)) >= {"f", "i", "b"}          # each kind is exercised
    assert len(P.pack(params)) == sum(map(len, ks))
    _assert_round_trip(params)


@pytest.mark.parametrize("integrator", sorted(NAMES))
def test_negative_zero_and_the_extremes_of_each_kind_come_back(integrator):
    """Each field in turn set to a value a careless packing loses: -0.0, NaN, ±inf and
    the smallest subnormal for a float, the largest exact int of either sign, each bool."""
    params = _params(integrator)
    extremes = {"f": (-0.0, math.nan, math.inf, -math.inf, 5e-324, -1.7976931348623157e308),
                "i": (2**53 - 1, -(2**53 - 1), 0, -1),
                "b": (True, False)}
    for k, t in enumerate(params):
        for j, field in enumerate(t._fields):
            for x in extremes[P.kind(t[j])]:
                changed = (*params[:k], t._replace(**{field: x}), *params[k + 1:])
                _assert_round_trip(changed)
                if x == 0.0 and isinstance(x, float):
                    row = P.pack(changed)
                    assert math.copysign(1.0, row[sum(map(len, params[:k])) + j]) == -1.0


class Mixed(NamedTuple):
    a: np.float64
    n: np.int32
    flag: np.bool_
    table: tuple
    x: float


def test_numpy_scalars_count_as_their_kind_and_other_values_come_from_the_prototype():
    proto = Mixed(np.float64(-0.0), np.int32(-7), np.bool_(True), (1, 2), 2.5)
    assert P.kinds((proto,)) == ("fibvf",)
    row = P.pack((proto,))
    assert row == [-0.0, -7.0, 1.0, 2.5]
    (back,) = P.rebuild((proto,), np.array(row))
    assert back.table is proto.table
    assert _same(back.a, -0.0) and back.n == -7 and back.flag is True and back.x == 2.5
    # a value that is not packed is part of the family; a scalar's value is not
    assert P.family((proto,)) != P.family((proto._replace(table=(1, 3)),))
    assert P.family((proto,)) == P.family((proto._replace(a=np.float64(4.0)),))
    assert P.family((proto,)) != P.family((proto._replace(a=4.0),))       # another type


def test_the_exact_callers_refuse_other_types_and_ints_a_double_cannot_hold():
    proto = Mixed(np.float64(1.0), np.int32(1), np.bool_(True), (), 1.0)
    with pytest.raises(TypeError, match="float64"):
        P.kinds((proto,), exact=True)
    with pytest.raises(TypeError, match="float64"):
        P.pack((proto,), exact=True)
    with pytest.raises(TypeError, match="Mixed"):
        P.rebuild_source(P.kinds((proto,)), "p", ["Mixed"])    # no prototype to read
    scheme, *rest = _params("energy")
    ints = [f for f, x in zip(scheme._fields, scheme) if P.kind(x) == "i"]
    for big in (2**53, -(2**53), 2**63):
        with pytest.raises(ValueError, match="2\\*\\*53"):
            P.pack((scheme._replace(**{ints[0]: big}), *rest))


def test_the_compiled_rebuild_reads_the_same_values():
    """The overload the CPU batch kernel compiles (kinds from Numba's types, the same
    generator) gives the Python version's values: the default run's tuples, and a tuple
    with NumPy scalars and a value taken from the prototype."""
    from numba import njit

    @njit
    def compiled(protos, row):
        return P.rebuild(protos, row)

    for params in (_params("energy"), (Mixed(np.float64(-0.0), np.int32(-7), np.bool_(True),
                                              (1, 2), 2.5),)):
        row = np.array(P.pack(params))
        for a, b in zip(compiled(params, row), P.rebuild(params, row)):
            assert type(a) is type(b)
            for x, y in zip(a, b):
                assert _same(x.item() if isinstance(x, np.generic) else x, y), (x, y)
