"""A sweep's grid: values per configuration key, their Cartesian product, the point configs.

A key's values are a list (``0,1,10,100`` on the command line, any sequence in Python) or a
range, ``linspace(a, b, n)`` (n evenly spaced values from a to b) or ``logspace(a, b, n)``
(n values from 10^a to 10^b, as ``numpy.logspace``).  The product runs over the keys in the
order given, the last key fastest, so point ``i`` is row ``i`` of ``numpy.ndindex(shape)``.
"""
from __future__ import annotations

import itertools
import json
import math
import re
from dataclasses import dataclass
from typing import Any, Iterator, Mapping

import numpy as np

from ..config import (CROSS_CHECKS, RUN_CHECKS, Config, field_spec, number_with_unit,
                      parse_value)
from ..output.estimate import check_count_limit
from .errors import BadGridItem, TooManyPoints

__all__ = ["Grid", "parse_grid_option", "format_value", "MAX_POINTS"]

_RANGE = re.compile(r"^\s*(linspace|logspace)\s*\((.*)\)\s*$")
MAX_POINTS = 10**6      # points a grid may have unless the caller raises the limit


def _field(key: str):
    return field_spec(key)


def _range_args(key: str, kind: str, args: str) -> tuple[float, float, int]:
    parts = [p.strip() for p in args.split(",")]
    usage = f"grid {key}: {kind}(a, b, n) takes two numbers and a whole number n >= 1"
    if len(parts) != 3:
        raise ValueError(f"{usage}, got {kind}({args})")
    try:
        a, b = float(parts[0]), float(parts[1])
        n = float(parts[2])
    except ValueError:
        raise ValueError(f"{usage}, got {kind}({args})") from None
    if (not (math.isfinite(a) and math.isfinite(b)) or not math.isfinite(n)
            or not n.is_integer() or n < 1):
        raise ValueError(f"{usage}, got {kind}({args})")
    return a, b, int(n)


def _count(key: str, vals) -> int:
    """How many values ``vals`` gives ``key``, without making them."""
    if isinstance(vals, str):
        m = _RANGE.match(vals)
        if m:
            return _range_args(key, m.group(1), m.group(2))[2]
        return sum(1 for t in vals.split(",") if t.strip())
    if np.isscalar(vals):
        return 1
    try:
        return len(vals)
    except TypeError:
        raise ValueError(f"grid {key}: values must be a list, an array or text such as "
                         f"'linspace(0, 1, 5)', got {type(vals).__name__}") from None


def _check_size(counts: dict[str, int], max_points: float) -> None:
    """TooManyPoints naming the count if the grid of these axis lengths is too large; a
    ValueError if ``max_points`` is no limit (``output.estimate.check_count_limit``)."""
    check_count_limit("max_points", max_points)
    if math.prod(counts.values()) > max_points:
        raise TooManyPoints(counts, max_points)


def _values_from_text(key: str, text: str) -> list[Any]:
    m = _RANGE.match(text)
    if m:
        a, b, n = _range_args(key, m.group(1), m.group(2))
        fn = np.linspace if m.group(1) == "linspace" else np.logspace
        return fn(a, b, n).tolist()
    items = [s.strip() for s in text.split(",")]
    if items and items[-1] == "" and any(items[:-1]):
        items.pop()                  # a trailing comma: "1,2,"
    if not any(items):
        raise ValueError(f"grid {key}: no values given ({_forms(key)})")
    if "" in items:
        raise ValueError(f"grid {key}: value {items.index('') + 1} of {text.strip()!r} is "
                         f"empty (give values separated by single commas, e.g. 1,2,3)")
    values = [parse_value(key, item) for item in items]
    if _field(key).kind in ("int", "float"):
        for item, value in zip(items, values):
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                continue
            if number_with_unit(item) is not None:
                break           # the key's own message: values are SI numbers
            where = f"grid {key}" + ("" if item == text.strip() else f" = {text.strip()!r}")
            raise ValueError(f"{where}: {item!r} is not a number; {_forms(key)}")
    return values


def _forms(key: str) -> str:
    """The forms a grid's values take, for messages."""
    return (f"give the values as a comma-separated list ({key}=0,1,10,100), "
            f"linspace(a,b,n) (n values from a to b: {key}=linspace(0,100,11)) or "
            f"logspace(a,b,n) (n values from 10^a to 10^b)")


def _coerce(key: str, values) -> tuple[Any, ...]:
    """Check every value against the key's type and range (one line naming both)."""
    spec = _field(key)
    if (spec.kind == "float" and all(type(v) is float for v in values)
            and all(map(math.isfinite, values))):
        # the common case (ranges, float lists): only the range is left to check
        out = values
        bad = next((v for v in out if not spec.check(v)), None) if spec.check else None
        if bad is not None:
            spec.coerce(key, bad)     # raises, naming the key and its range
    else:
        out = []
        for value in values:
            if isinstance(value, np.generic):
                value = value.item()
            if isinstance(value, str) and spec.kind != "str":
                value = parse_value(key, value)
            out.append(spec.coerce(key, value))
    if len(set(out)) != len(out):
        seen = set()
        for value in out:
            if value in seen:
                raise ValueError(f"grid {key} lists the value {value!r} twice")
            seen.add(value)
    if not out:
        raise ValueError(f"grid {key}: no values given")
    return tuple(out)


def format_value(value: Any) -> str:
    """A value as it is written in names and tables: shortest round-trip form."""
    if isinstance(value, float):
        text = repr(value)
        return text[:-2] if text.endswith(".0") else text
    return str(value)


@dataclass(frozen=True)
class Grid:
    """The swept keys (in order) and their values; points are their Cartesian product.

    ``len(grid)`` is the number of points; point ``i`` is the ``i``-th of the product in
    row-major order (the last key varies fastest).

    Attributes
    ----------
    keys : tuple of str
        The swept configuration keys.
    values : tuple of tuple
        Each key's values, checked against its type and range.
    """

    keys: tuple[str, ...]
    values: tuple[tuple[Any, ...], ...]

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any] | Grid, max_points: float = MAX_POINTS) -> Grid:
        """A grid from key -> values.

        Parameters
        ----------
        spec : Mapping or Grid
            ``{"rod.mu": [0, 1, 10], "floor.beta": "linspace(0.01, 0.05, 3)"}``: lists,
            arrays, scalars, or text as on the command line (``"0,1,10"``,
            ``"linspace(a, b, n)"``, ``"logspace(a, b, n)"``); a Grid is returned as is.
        max_points : float, optional
            The most points the grid may have; its size is counted from the lengths and the
            ``linspace``/``logspace`` counts before any value is made.

        Returns
        -------
        Grid

        Raises
        ------
        ValueError
            An empty spec, an unknown key, a value outside its key's range, more than
            ``max_points`` points (naming the count), or a ``max_points`` that is not a
            whole number >= 1 (or ``math.inf``).
        """
        if isinstance(spec, Grid):
            _check_size(dict(zip(spec.keys, spec.shape)), max_points)
            return spec
        if not isinstance(spec, Mapping) or not spec:
            raise ValueError("grid must map at least one configuration key to its values, "
                             "e.g. {'rod.mu': [0, 1, 10]}")
        for key in spec:
            if _field(str(key)).kind == "times":
                raise ValueError(f"grid {key}: a list of times is one value for the whole "
                                 f"sweep, not a swept key; set it in the base "
                                 f"configuration")
            if str(key) == "output.observer":
                raise ValueError(f"grid {key}: the observer gives the sweep's columns, one "
                                 f"for the whole sweep, not a swept key; set it in the base "
                                 f"configuration")
        _check_size({key: _count(key, vals) for key, vals in spec.items()}, max_points)
        keys, values = [], []
        for key, vals in spec.items():
            if isinstance(vals, str):
                vals = _values_from_text(key, vals)
            elif np.isscalar(vals):
                vals = [vals]
            keys.append(key)
            values.append(_coerce(key, vals.tolist() if isinstance(vals, np.ndarray)
                                  else list(vals)))
        return cls(tuple(keys), tuple(values))

    @classmethod
    def from_json(cls, text: str) -> "Grid":
        """The grid a sweep file stores (``to_json``); its size was allowed when written.

        Parameters
        ----------
        text : str
            JSON ``{"key": [values...], ...}``.

        Returns
        -------
        Grid
        """
        return cls.from_spec(json.loads(text), max_points=math.inf)

    def to_json(self) -> str:
        """The grid as stored in a sweep file: ``{"key": [values...], ...}`` in order."""
        return json.dumps({k: list(v) for k, v in zip(self.keys, self.values)})

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of values per key, in key order."""
        return tuple(len(v) for v in self.values)

    def __len__(self) -> int:
        return math.prod(self.shape)

    def point(self, index: int) -> dict[str, Any]:
        """The overrides of point ``index`` (``{"rod.mu": 10.0, ...}``).

        Parameters
        ----------
        index : int
            The point number, from 0 (row-major: the last key varies fastest).

        Returns
        -------
        dict
            Swept key -> value.

        Raises
        ------
        IndexError
            ``index`` is outside the grid.
        """
        if not 0 <= index < len(self):
            raise IndexError(f"point {index} is outside the grid of {len(self)} points")
        idx = np.unravel_index(index, self.shape)
        return {k: v[i] for k, v, i in zip(self.keys, self.values, idx)}

    def points(self) -> Iterator[dict[str, Any]]:
        """Every point's overrides, in grid order.

        Yields
        ------
        dict
            Swept key -> value.
        """
        for combo in itertools.product(*self.values):
            yield dict(zip(self.keys, combo))

    def describe(self, index: int) -> str:
        """``rod.mu=10 floor.beta=0.05``: point ``index`` in a line.

        Parameters
        ----------
        index : int
            The point number, from 0 (row-major: the last key varies fastest).

        Returns
        -------
        str
        """
        return " ".join(f"{k}={format_value(v)}" for k, v in self.point(index).items())

    def run_name(self, index: int) -> str:
        """File name of the point's run for ``--save-runs``: the index (zero-padded, so the
        names sort in grid order) then each swept key and value; the same grid always gives
        the same names.

        Parameters
        ----------
        index : int
            The point number, from 0 (row-major: the last key varies fastest).

        Returns
        -------
        str
            A portable file name ending in ``.h5``.
        """
        width = len(str(max(len(self) - 1, 0)))
        parts = [f"{index:0{width}d}"]
        for k, v in self.point(index).items():
            parts.append(f"{k}={format_value(v)}")
        name = "_".join(parts)
        return re.sub(r"[^A-Za-z0-9._=+-]", "-", name) + ".h5"

    def config(self, base: Config, index: int) -> Config:
        """Point ``index``'s configuration: ``base`` with the point's values.

        Parameters
        ----------
        base : Config
            The sweep's base configuration.
        index : int
            The point number, from 0.

        Returns
        -------
        Config

        Raises
        ------
        ValueError
            The point's configuration is invalid, naming the point and the field.
        """
        try:
            return base.override(self.point(index))
        except ValueError as exc:
            raise ValueError(f"grid point {index} ({self.describe(index)}): {exc}") from None

    def combinations(self, keys) -> Iterator[tuple[int, dict[str, Any]]]:
        """The distinct combinations of the swept keys among ``keys``.

        Whatever depends only on ``keys`` is the same at every point of a combination, so it
        needs checking or computing once per combination.

        Parameters
        ----------
        keys : Iterable of str
            Dotted configuration keys; those not swept are ignored.

        Yields
        ------
        tuple of (int, dict)
            The flat index of the first point with the combination, and its overrides
            ``{key: value}``.
        """
        axes = [j for j, k in enumerate(self.keys) if k in keys]
        if not axes:
            yield 0, {}
            return
        for combo in itertools.product(*(range(len(self.values[j])) for j in axes)):
            idx = [0] * len(self.keys)
            for j, i in zip(axes, combo):
                idx[j] = i
            index = int(np.ravel_multi_index(idx, self.shape))
            yield index, {self.keys[j]: self.values[j][i] for j, i in zip(axes, combo)}

    def multiplicity(self, keys) -> int:
        """How many points share each combination of ``combinations(keys)``.

        Parameters
        ----------
        keys : Iterable of str
            Dotted configuration keys.

        Returns
        -------
        int
            The product of the lengths of the swept axes not among ``keys``.
        """
        return math.prod(len(v) for k, v in zip(self.keys, self.values) if k not in keys)

    def validate(self, base: Config) -> None:
        """Check every point's configuration before anything runs or is written, in time
        that grows with the values, not the points: each key's values were checked on
        their own when the grid was made; the checks that relate keys (``CROSS_CHECKS``,
        and ``RUN_CHECKS``: what a run refuses) run over the combinations of the swept
        keys they name.

        Parameters
        ----------
        base : Config
            The sweep's base configuration.

        Raises
        ------
        ValueError
            The first invalid point, naming it, the field and its range.
        """
        flat = base.flat()
        for keys, check in RUN_CHECKS:   # what every point runs unless a key is swept
            if not set(keys) & set(self.keys):
                check(*(flat[k] for k in keys))
        for keys, check in CROSS_CHECKS + RUN_CHECKS:
            if not set(keys) & set(self.keys):
                continue
            for index, over in self.combinations(keys):
                try:
                    check(*(over.get(k, flat[k]) for k in keys))
                except ValueError as exc:
                    raise ValueError(f"grid point {index} ({self.describe(index)}): "
                                     f"{exc}") from None


def parse_grid_option(items) -> dict[str, str]:
    """``("rod.mu=0,1,10", "floor.beta=linspace(0.01,0.05,3)")`` -> ordered spec dict;
    BadGridItem (a ValueError) for an item without ``KEY=``, a key given twice, or none."""
    spec: dict[str, str] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise BadGridItem("form", item=item)
        if key in spec:
            raise BadGridItem("twice", key=key)
        spec[key] = text
    if not spec:
        raise BadGridItem("none")
    return spec
