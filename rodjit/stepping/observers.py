"""Observers: compiled code of one's own that watches every accepted step of a run, keeps a
fixed-size state, gives named values at the end and may end the run (an event).

An observer is four compiled functions (``rodjit._jit.kernel``: they must not allocate) of
its parameters ``p`` (a NamedTuple, one class per observer) and its state ``st`` (a float64
array of ``size`` entries, zero at the start of a run)::

    start(p, st, system, rod, floor, t, u, v)              # once, at the initial state
    step(p, st, system, rod, floor, t0, t1, u0, v0, u1, v1)
                                         # after each accepted step from t0 to t1
    stop(p, st) -> bool                  # True: the run ends here (an event)
    values(p, st, out)                   # its ``columns`` into ``out``

``system`` is the rod's ``model.system.RodSystem`` (node spacing ``h``, gravity ``g``, ...),
``rod`` and ``floor`` the parameters of its stress laws (``rodjit.laws.value(x, floor)`` is
the floor's stress in compiled code); ``u``, ``v`` are the heights and velocities of the
N + 1 nodes.  ``register`` makes it
selectable as ``output.observer``.  The compiled loop calls it inside the time loop
(``loop.start``, ``loop.advance``: its type is a sixth parameter tuple, so the loop is
compiled for it and a run without one compiles nothing of it), ``stop`` where the loop
checks ``time.stop_after_bounces`` (``events.stop_due``), and ``values`` after every
compiled call, into the tail of its state array (``arrays.RunArrays.observed``).  So every
engine reads the same values from the same compiled code: a single run
(``Result.observed``), the run file's checkpoint (which keeps the state, so a resumed run
observes as an uninterrupted one), the CPU batch engine and the GPU engine (sweep summary
columns).  ``values`` must be a function of the state: it is called more than once.

An observer sees the states at the ends of the accepted steps, not between them: an extremum
inside a step is seen at the step's nearer end (the steps are short in contact, where the
rod's state changes fastest).  ``NoObserver``, the default, does nothing.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, NamedTuple

from .._jit import kernel, overload, python_function
from . import registered

__all__ = ["Observer", "NoObserver", "register", "get_observer", "observer_names",
           "observer_of", "params_of", "state_size", "columns_of", "observe_start",
           "observe_step", "observe_stop", "observe_values"]


@dataclass(frozen=True)
class Observer:
    """An observer (module docstring).

    Parameters
    ----------
    name : str
        What ``output.observer`` names it by.
    params : type
        Its parameters' NamedTuple class (one class per observer: the compiled loop picks
        the observer by it); its fields floats, ints or bools, run-time values in compiled
        code, so a sweep over them compiles once.
    columns : dict
        Its values' names -> descriptions, in the order ``values`` writes them: they become
        ``Result.observed``'s keys and sweep summary columns.
    size : int
        The entries of its state.
    start, step, stop, values : kernels
        Its compiled functions (module docstring).
    from_config : callable, optional
        ``from_config(config) -> params`` for a run's ``Config`` (default: ``params()``).
    """

    name: str
    params: type
    columns: dict
    size: int
    start: Any
    step: Any
    stop: Any
    values: Any
    from_config: Callable[[Any], Any] | None = field(default=None, compare=False)


class NoObserver(NamedTuple):
    """The parameters of the default observer, which does nothing."""


@kernel
def _no_start(p, st, system, rod, floor, t, u, v):
    pass


@kernel
def _no_step(p, st, system, rod, floor, t0, t1, u0, v0, u1, v1):
    pass


@kernel
def _no_stop(p, st):
    return False


@kernel
def _no_values(p, st, out):
    pass


_BY_TYPE: dict[type, Observer] = {}
_BY_NAME: dict[str, Observer] = {}


def register(observer: Observer) -> Observer:
    """Make ``observer`` selectable as ``output.observer`` and known to the compiled loop.

    Registering the same ``Observer`` again is a no-op.

    Parameters
    ----------
    observer : Observer
        The observer to register.

    Returns
    -------
    Observer
        ``observer`` itself.

    Raises
    ------
    TypeError
        A part of the wrong kind (``params`` not a NamedTuple class, a function not
        compiled), or a function that fails a dry run (``_dry_run``), named in the
        message.
    ValueError
        Its name is taken or not letters, digits, '-' and '_', its parameter class belongs
        to another observer, its ``size`` is negative, or a column is not an identifier.
        (A column named as a built-in summary column is refused by the sweep that would
        hold both, ``sweeps.point.observer_columns``.)
    """
    if not isinstance(observer, Observer):
        raise TypeError(f"register takes an Observer, not {type(observer).__name__}")
    if not (isinstance(observer.params, type) and issubclass(observer.params, tuple)
            and hasattr(observer.params, "_fields")):
        raise TypeError(f"observer {observer.name!r}: params must be a NamedTuple class")
    for part in ("start", "step", "stop", "values"):
        if not hasattr(getattr(observer, part), "py_func"):
            raise TypeError(f"observer {observer.name!r}: {part} must be compiled "
                            f"(rodjit.observers.observer_kernel)")
    if not isinstance(observer.size, int) or observer.size < 0:
        raise ValueError(f"observer {observer.name!r}: size must be an int >= 0, not "
                         f"{observer.size!r}")
    if not observer.name or not all(c.isalnum() or c in "-_" for c in observer.name):
        raise ValueError(f"observer name {observer.name!r} must be letters, digits, '-' "
                         f"or '_'")
    if observer.params in _BY_TYPE:
        if _BY_TYPE[observer.params] is not observer:
            raise ValueError(f"parameter type {observer.params.__name__} already belongs to "
                             f"another observer")
        return observer
    if observer.name in _BY_NAME:
        raise ValueError(f"an observer named {observer.name!r} is registered already")
    for column in observer.columns:
        if not (isinstance(column, str) and column.isidentifier()):
            raise ValueError(f"observer {observer.name!r}: column {column!r} must be an "
                             f"identifier")
    _dry_run(observer)
    # named through the cache namespace by an alias that identifies the implementation:
    # compiled code cached for one observer is never loaded for another of the same name
    registered.adopt(observer.params, f"observer_{observer.name}",
                     (observer.start, observer.step, observer.stop, observer.values))
    _BY_TYPE[observer.params] = observer
    _BY_NAME[observer.name] = observer
    return observer


def _dry_run(observer: Observer) -> None:
    """Call the observer's Python functions once on a small rod (zero parameters, NumPy
    arrays of the sizes the loop gives them), so a wrong signature, a read or write past
    its state or its ``out``, or a ``stop`` that answers no bool is refused at ``register``
    in one line, not as a compile error in a run's first call (compiled code does not
    check bounds)."""
    import numpy as np

    from ..model.laws import AikiKosugiFloor, AikiKosugiRod
    from ..model.system import RodSystem

    kinds = getattr(observer.params, "__annotations__", {})
    zero = {bool: False, "bool": False, int: 0, "int": 0}
    p = observer.params(*(zero.get(kinds.get(f), 0.0) for f in observer.params._fields))
    system = RodSystem(4, 0.25, 0.0, 0.0, -9.81)
    u = np.linspace(0.1, 1.1, 5)
    v = np.zeros(5)
    st = np.zeros(observer.size)
    out = np.zeros(len(observer.columns))
    rod, floor = AikiKosugiRod(1000.0), AikiKosugiFloor(1000.0, 0.05)
    calls = (("start", (p, st, system, rod, floor, 0.0, u, v)),
             ("step", (p, st, system, rod, floor, 0.0, 1e-3, u, v, u + 1e-3, v)),
             ("stop", (p, st)), ("values", (p, st, out)))
    for part, args in calls:
        try:
            got = python_function(getattr(observer, part))(*args)
        except Exception as exc:
            raise TypeError(f"observer {observer.name!r}: {part} fails a dry run on a rod of "
                            f"4 segments: {type(exc).__name__}: {exc}") from None
        if part == "stop" and not isinstance(got, (bool, np.bool_)):
            raise TypeError(f"observer {observer.name!r}: stop must return a bool, not "
                            f"{type(got).__name__}")


def get_observer(name: str) -> Observer:
    """The observer registered as ``name``.

    Parameters
    ----------
    name : str
        Its name (``output.observer``); "" or "none": ``NoObserver``'s.

    Returns
    -------
    Observer

    Raises
    ------
    ValueError
        No observer is registered as ``name`` (the message names the registered ones).
    """
    got = _BY_NAME.get("none" if name == "" else name)
    if got is None:
        raise ValueError(f"output.observer = {name!r} is not a registered observer; choose "
                         f"one of {observer_names()}")
    return got


def observer_names() -> list[str]:
    """The names ``output.observer`` takes."""
    return sorted(_BY_NAME)


def observer_of(params) -> Observer:
    """The observer whose parameter class ``params`` (a class or an instance) is."""
    return _BY_TYPE[params if isinstance(params, type) else type(params)]


def params_of(config) -> Any:
    """The observer parameters of a run's ``Config`` (without ``from_config``, one shared
    ``params()``: the points of a sweep share their parameter tuples where they agree)."""
    ob = get_observer(config.output.observer)
    if ob.from_config is not None:
        return ob.from_config(config)
    return _DEFAULTS.setdefault(ob.params, ob.params())


_DEFAULTS: dict[type, Any] = {}


def state_size(params) -> int:
    """The entries of ``RunArrays.observed`` for the observer of ``params``: its state,
    then its values."""
    ob = observer_of(params)
    return ob.size + len(ob.columns)


def columns_of(config) -> dict:
    """The columns (name -> description) of the observer of a run's ``Config``."""
    return dict(get_observer(config.output.observer).columns)


def values_of(params, observed) -> dict:
    """``{column: value}`` from a run's ``observed`` array (the values at its tail)."""
    ob = observer_of(params)
    return {c: float(x) for c, x in zip(ob.columns, observed[ob.size:])}


# Generic entry points: the loop calls these; the overloads pick the observer by the Numba
# type of its parameters at compile time (as ``model.laws`` does for laws).
def observe_start(p, st, system, rod, floor, t, u, v):
    """The observer's ``start`` (zeroed state ``st``)."""
    python_function(_BY_TYPE[type(p)].start)(p, st, system, rod, floor, t, u, v)


def observe_step(p, st, system, rod, floor, t0, t1, u0, v0, u1, v1):
    """The observer's ``step`` after the accepted step from (t0, u0, v0) to (t1, u1, v1)."""
    python_function(_BY_TYPE[type(p)].step)(p, st, system, rod, floor, t0, t1, u0, v0, u1,
                                            v1)


def observe_stop(p, st):
    """Whether the observer ends the run now."""
    return bool(python_function(_BY_TYPE[type(p)].stop)(p, st))


def observe_values(p, st):
    """The observer's values into the tail of ``st`` (after its ``size`` state entries)."""
    ob = _BY_TYPE[type(p)]
    python_function(ob.values)(p, st[:ob.size], st[ob.size:])


def _of(p) -> Observer:
    cls = getattr(p, "instance_class", None)
    if cls not in _BY_TYPE:
        raise TypeError(f"{p} is not the parameter type of a registered observer")
    return _BY_TYPE[cls]


@overload(observe_start)
def _start_ov(p, st, system, rod, floor, t, u, v):
    impl = _of(p).start
    return lambda p, st, system, rod, floor, t, u, v: impl(p, st, system, rod, floor, t, u,
                                                           v)


@overload(observe_step)
def _step_ov(p, st, system, rod, floor, t0, t1, u0, v0, u1, v1):
    impl = _of(p).step
    return (lambda p, st, system, rod, floor, t0, t1, u0, v0, u1, v1:
            impl(p, st, system, rod, floor, t0, t1, u0, v0, u1, v1))


@overload(observe_stop)
def _stop_ov(p, st):
    impl = _of(p).stop
    return lambda p, st: impl(p, st)


@overload(observe_values)
def _values_ov(p, st):
    ob = _of(p)
    size = ob.size
    impl = ob.values
    return lambda p, st: impl(p, st[:size], st[size:])


register(Observer("none", NoObserver, {}, 0, _no_start, _no_step, _no_stop, _no_values))
