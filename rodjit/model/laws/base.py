"""The stress-law interface and its compile-time dispatch.

A law is a singular stress ``s(x)`` on ``x > lower(p)`` with its derivative and its
primitive (zero at 0).  Its parameters travel as an instance of a law-specific NamedTuple,
so the compiled kernels pick the law from the *type* of the parameters (no run-time branch,
one compilation per law, parameter values stay run-time arguments, on-disk cache works).
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Any, Callable, NamedTuple

from . import registered
from ..._jit import overload, python_function

__all__ = ["Law", "register", "law_of", "law_for_numba_type", "get_law", "law_names", "value",
           "deriv", "primitive", "lower", "max_deriv"]


@dataclass(frozen=True)
class Law:
    """A stress law, made selectable by ``register``.

    ``deriv_max(lo, hi, params)`` (optional, compiled like the others) returns the largest
    derivative on [lo, hi]; the kernels call it with the smallest and largest segment
    strain to bound the stiffness, instead of evaluating ``deriv`` on every segment.  Give
    it when the law allows it exactly (``deriv(lo)`` when the derivative decreases,
    ``max(deriv(lo), deriv(hi))`` when it is convex); without it the kernels scan.

    ``difference(a, b, params)`` (optional, compiled) returns the divided difference of the
    primitive q = (P(b) − P(a))/(b − a), its slope ∂q/∂b and the stress s(b), in closed
    form sharing their work (one division for all three in the Aiki–Kosugi laws), accurate
    also as b → a (where q, ∂q/∂b must give s(a) and s'(a)/2); the energy integrator calls
    it twice per segment and step.  Without it ``kernels.discrete_gradient`` evaluates q by
    Gauss–Legendre quadrature or the exact quotient, a few evaluations of ``value`` and
    ``deriv`` each (see there for the accuracy a closed form must match).

    Parameters
    ----------
    name : str
        The name ``rod.law`` / ``floor.law`` selects it by.
    kind : str
        ``"rod"`` (stress f of the strain, tension positive) or ``"floor"`` (upward floor
        stress σ_b of the bottom height).
    params : type
        The NamedTuple class of its parameters (one class per law: the kernels dispatch on
        it).
    from_config : callable
        Builds a ``params`` instance from the matching config section (``RodConfig`` or
        ``FloorConfig``).
    value, deriv, primitive : callable
        Compiled (``law_kernel``) functions of ``(x, params)``: the stress, its derivative
        and its primitive (zero at x = 0).
    lower : callable
        Compiled function of ``(params)``: the lower end of the domain (admissible states
        have x > lower).
    description : str
        The formula, one line, for listings.
    deriv_max : callable, optional
        Compiled ``(lo, hi, params)`` -> the largest derivative on [lo, hi].
    difference : callable, optional
        Compiled ``(a, b, params)`` -> (divided difference of the primitive, its slope in
        b, the stress at b).
    extension, extension_deriv : callable, optional
        Floor laws only: compiled ``(x, params)`` -> the contact branch (x ≤ 0) continued
        smoothly past 0, and its derivative.  With both, the embedded pairs take each trial
        step with the law of the side of the contact switch the step starts on
        (``Sided``) and end the step where it leaves that side, so no step integrates
        across the switch's kink; without them the pairs step with the law itself.
    """

    name: str
    kind: str
    params: type
    from_config: Callable[[Any], Any]
    value: Callable
    deriv: Callable
    primitive: Callable
    lower: Callable
    description: str = ""
    deriv_max: Callable | None = None
    difference: Callable | None = None
    extension: Callable | None = None
    extension_deriv: Callable | None = None


class Sided(NamedTuple):
    """A floor law held to one side of its contact switch at x = 0 (``side``): ``FREE``
    (σ_b ≡ 0, the law above the floor continued below it), ``CONTACT`` (the contact branch
    continued above 0, ``Law.extension``), or ``BOTH`` (the law itself).  An explicit pair
    takes each trial step with the side its start is on, so the force along the step is
    smooth and the pair's error estimate holds; the loop ends a step that leaves its side
    on the crossing."""

    law: Any
    side: int


BOTH = 0
FREE = 1
CONTACT = 2


def is_sided_type(numba_type) -> bool:
    """Whether a Numba type is that of ``Sided`` parameters."""
    return getattr(numba_type, "instance_class", None) is Sided


def has_extension(params_cls) -> bool:
    """Whether the law of the parameter class ``params_cls`` continues its contact branch
    past 0 (``Law.extension`` and ``Law.extension_deriv``)."""
    law = _BY_TYPE.get(params_cls)
    return law is not None and law.extension is not None and law.extension_deriv is not None


_BY_TYPE: dict[type, Law] = {}
_BY_NAME: dict[tuple[str, str], Law] = {}


def register(law: Law) -> Law:
    """Make a law available to the kernels and to ``rod.law`` / ``floor.law``.

    Registering the same ``Law`` again is a no-op.

    Parameters
    ----------
    law : Law
        The law to register.

    Returns
    -------
    Law
        ``law`` itself.

    Raises
    ------
    TypeError
        ``law`` is not a ``Law``, its ``params`` not a NamedTuple class, its
        ``from_config`` not callable, or one of its functions not compiled (a plain Python
        function, None): refused here, naming the field, not when a run first compiles it.
    ValueError
        ``law.kind`` is neither ``"rod"`` nor ``"floor"``, or its parameter class belongs
        to another registered law.
    """
    _check_parts(law)
    if law.kind not in ("rod", "floor"):
        raise ValueError(f"law kind must be 'rod' or 'floor', not {law.kind!r}")
    if law.params in _BY_TYPE:
        if _BY_TYPE[law.params] is not law:
            raise ValueError(f"parameter type {law.params.__name__} already belongs to "
                             f"another law")
        return law
    # name the parameter class through the `registered` namespace (see its docstring), by
    # a name that identifies the implementation: compiled code cached for one law must
    # never be loaded for another registered under the same name elsewhere
    alias = (f"{law.kind}_{''.join(c if c.isalnum() else '_' for c in law.name)}_"
             f"{_fingerprint(law)}")
    law.params.__module__ = registered.__name__
    law.params.__qualname__ = alias
    setattr(registered, alias, law.params)
    _BY_TYPE[law.params] = law
    _BY_NAME[(law.kind, law.name)] = law
    return law


_REQUIRED = ("value", "deriv", "primitive", "lower")
_OPTIONAL = ("deriv_max", "difference", "extension", "extension_deriv")


def _check_parts(law: Any) -> None:
    """TypeError naming ``register``'s argument or the field of it that is not what a law
    needs (``register``)."""
    if not isinstance(law, Law):
        raise TypeError(f"register(law): law must be a rodjit.laws.Law, not "
                        f"{_shown(law)}")
    params = law.params
    if not (isinstance(params, type) and issubclass(params, tuple)
            and hasattr(params, "_fields")):
        raise TypeError(f"register(law): law.params must be a NamedTuple class (the law's "
                        f"parameters), not {_shown(params)}")
    if not callable(law.from_config):
        raise TypeError(f"register(law): law.from_config must be callable (config section "
                        f"-> {params.__name__}), not {_shown(law.from_config)}")
    for name in _REQUIRED + _OPTIONAL:
        function = getattr(law, name)
        if function is None and name in _OPTIONAL:
            continue
        # a law_kernel (``_jit.Kernel``) or a Numba dispatcher: both keep the Python
        # function they compile as ``py_func``; a plain function would fail only when a
        # run first compiles the loop with it
        if not hasattr(function, "py_func"):
            raise TypeError(f"register(law): law.{name} must be a compiled function "
                            f"(decorate it with rodjit.laws.law_kernel), not "
                            f"{_shown(function)}")


def _shown(value: Any) -> str:
    """How a refusal shows a value: a function by its name, anything else by its repr
    (cut short), with its type."""
    if callable(value) and hasattr(value, "__qualname__"):
        return f"the plain Python function {value.__qualname__!r}" if isinstance(
            value, type(_shown)) else f"{value.__qualname__!r} ({type(value).__name__})"
    text = repr(value)
    return f"{text if len(text) <= 40 else text[:37] + '...'} ({type(value).__name__})"


def _fingerprint(law: Law) -> str:
    """Hash of where and how the law is defined: module, names and code of its parts."""
    h = hashlib.sha1()
    parts = [law.params] + [getattr(f, "py_func", f) for f in
                            (law.value, law.deriv, law.primitive, law.lower, law.deriv_max,
                             law.difference, law.extension, law.extension_deriv)
                            if f is not None]
    for obj in parts:
        h.update(f"{obj.__module__}.{obj.__qualname__}".encode())
        code = getattr(obj, "__code__", None)
        if code is not None:
            h.update(code.co_code)
            h.update(repr(code.co_consts).encode())
            h.update(repr(code.co_names).encode())
        else:
            h.update(repr(getattr(obj, "_fields", ())).encode())
    return h.hexdigest()[:12]


def get_law(kind: str, name: str) -> Law:
    """The registered law ``name`` of ``kind``.

    Parameters
    ----------
    kind : str
        ``"rod"`` or ``"floor"``.
    name : str
        The law's name, e.g. ``"aiki-kosugi"``.

    Returns
    -------
    Law

    Raises
    ------
    ValueError
        No such law, naming the registered ones.
    """
    try:
        return _BY_NAME[(kind, name)]
    except KeyError:
        raise ValueError(
            f"{kind}.law = {name!r} is not a known {kind} law; choose one of {law_names(kind)}"
        ) from None


def law_names(kind: str) -> list[str]:
    """The names of the registered laws of ``kind``.

    Parameters
    ----------
    kind : str
        ``"rod"`` or ``"floor"``.

    Returns
    -------
    list of str
        Sorted names, each valid for ``rod.law`` / ``floor.law``.
    """
    return sorted(n for k, n in _BY_NAME if k == kind)


def law_of(params) -> Law:
    """The law whose parameters ``params`` are (plain Python side).

    Parameters
    ----------
    params : NamedTuple
        An instance of a registered law's parameter class.

    Returns
    -------
    Law

    Raises
    ------
    KeyError
        ``params`` is not the parameters of a registered law.
    """
    return _BY_TYPE[type(params)]


def law_for_numba_type(numba_type) -> Law:
    """The law whose parameters have the Numba type ``numba_type`` (for overloads that
    dispatch on a law at compile time)."""
    cls = getattr(numba_type, "instance_class", None)
    if cls not in _BY_TYPE:
        raise TypeError(f"{numba_type} is not the parameter type of a registered stress law")
    return _BY_TYPE[cls]


# Generic entry points.  Called from Python (or with NUMBA_DISABLE_JIT=1) they dispatch on
# the Python type; inside compiled code the overloads below resolve at typing time.
def value(x, p):
    """Stress at x, for the law ``p`` belongs to (callable from Python and compiled code).

    Parameters
    ----------
    x : float
        Strain (rod laws) or bottom height [m] (floor laws), > ``lower(p)``.
    p : NamedTuple
        The law's parameters.

    Returns
    -------
    float
        The stress [N].
    """
    if type(p) is Sided:
        return _sided_python(x, p, "value")
    return _BY_TYPE[type(p)].value(x, p)


def _sided_parts(law: Law, which: str):
    """``(the law's function, its contact-branch continuation or None)`` for ``which``
    ("value" or "deriv"): what ``Sided`` parameters choose between, from Python and in
    compiled code alike."""
    return getattr(law, which), getattr(law, "extension" if which == "value"
                                        else "extension_deriv")


def _sided_python(x, p, which):
    """``value`` or ``deriv`` of ``Sided`` parameters, from Python (``_sided`` makes the
    compiled ones)."""
    impl, ext = _sided_parts(_BY_TYPE[type(p.law)], which)
    if ext is None or p.side == BOTH:
        return python_function(impl)(x, p.law)
    return 0.0 if p.side == FREE else python_function(ext)(x, p.law)


def deriv(x, p):
    """Derivative of the stress at x.

    Parameters
    ----------
    x : float
        Strain or bottom height, > ``lower(p)``.
    p : NamedTuple
        The law's parameters.

    Returns
    -------
    float
    """
    if type(p) is Sided:
        return _sided_python(x, p, "deriv")
    return _BY_TYPE[type(p)].deriv(x, p)


def primitive(x, p):
    """Primitive of the stress, zero at x = 0 (the stored energy density).

    Parameters
    ----------
    x : float
        Strain or bottom height, > ``lower(p)``.
    p : NamedTuple
        The law's parameters.

    Returns
    -------
    float
    """
    if type(p) is Sided:       # as compiled: the law's own (``_primitive_ov``)
        p = p.law
    return _BY_TYPE[type(p)].primitive(x, p)


def lower(p):
    """Lower end of the law's domain: admissible states have x > lower(p).

    Parameters
    ----------
    p : NamedTuple
        The law's parameters.

    Returns
    -------
    float
        −1 for the Aiki–Kosugi rod, −β for the floor.
    """
    # from Python, the law's own Python function (``_jit.python_function``); compiled
    # code calls the kernel, through the overload below (``Sided``: the law's, as there)
    if type(p) is Sided:
        p = p.law
    return float(python_function(_BY_TYPE[type(p)].lower)(p))


def max_deriv(u, ih, lo, hi, p):
    """Largest derivative (and at least 0) over the segment strains (u_{i+1} − u_i)·ih − 1
    of u, whose smallest and largest values are lo and hi."""
    law = _BY_TYPE[type(p)]
    if law.deriv_max is not None:
        return max(0.0, law.deriv_max(lo, hi, p))
    m = 0.0
    for i in range(u.size - 1):
        m = max(m, law.deriv((u[i + 1] - u[i]) * ih - 1.0, p))
    return m


def _sided(which):
    """The compiled ``which`` ("value" or "deriv") of a ``Sided`` law's numba type."""
    def make(p):
        impl, ext = _sided_parts(law_for_numba_type(p.types[0]), which)
        if ext is None:
            return lambda x, p: impl(x, p.law)

        def sided(x, p):
            if p.side == FREE:
                return 0.0
            if p.side == CONTACT:
                return ext(x, p.law)
            return impl(x, p.law)
        return sided
    return make


@overload(value)
def _value_ov(x, p):
    if is_sided_type(p):
        return _sided("value")(p)
    impl = law_for_numba_type(p).value
    return lambda x, p: impl(x, p)


@overload(deriv)
def _deriv_ov(x, p):
    if is_sided_type(p):
        return _sided("deriv")(p)
    impl = law_for_numba_type(p).deriv
    return lambda x, p: impl(x, p)


@overload(primitive)
def _primitive_ov(x, p):
    if is_sided_type(p):
        impl = law_for_numba_type(p.types[0]).primitive
        return lambda x, p: impl(x, p.law)
    impl = law_for_numba_type(p).primitive
    return lambda x, p: impl(x, p)


@overload(lower)
def _lower_ov(p):
    if is_sided_type(p):
        impl = law_for_numba_type(p.types[0]).lower
        return lambda p: impl(p.law)
    impl = law_for_numba_type(p).lower
    return lambda p: impl(p)


@overload(max_deriv)
def _max_deriv_ov(u, ih, lo, hi, p):
    law = law_for_numba_type(p)
    if law.deriv_max is not None:
        bound = law.deriv_max
        return lambda u, ih, lo, hi, p: max(0.0, bound(lo, hi, p))
    d = law.deriv

    def scan(u, ih, lo, hi, p):
        m = 0.0
        for i in range(u.size - 1):
            m = max(m, d((u[i + 1] - u[i]) * ih - 1.0, p))
        return m

    return scan
