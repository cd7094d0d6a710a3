"""rodjit replaces one method of Numba's cache class (``_jit._tolerate_refused_cache_writes``:
Numba offers no supported way to tolerate a cache write the disk refuses).  These tests
fail when Numba changes what that replacement relies on: the method's name and signature,
the classes that inherit it, and that a compile calls it to write the cache."""
from __future__ import annotations

import importlib
import inspect
import sys

import pytest

numba = pytest.importorskip("numba")
from numba.core import caching, dispatcher  # noqa: E402

from rodjit import _jit  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def loaded():
    _jit.load_numba()


def test_the_replaced_method_keeps_numbas_name_and_signature():
    replaced = caching.Cache.save_overload
    assert getattr(replaced, "rodjit_tolerant", False)
    original = replaced.__wrapped__
    assert original.__qualname__ == "Cache.save_overload"
    assert list(inspect.signature(original).parameters) == ["self", "sig", "data"]
    # it writes through ``_save_overload``, which the refusal tests of test_cache.py replace
    assert "_save_overload" in inspect.getsource(original)


def test_every_cache_a_dispatcher_makes_inherits_the_replaced_method():
    assert dispatcher.Dispatcher.enable_caching.__code__.co_names.count("FunctionCache") == 1
    for cls in (caching.FunctionCache, *caching.Cache.__subclasses__()):
        assert "save_overload" not in vars(cls), cls      # no override bypasses ours
        assert cls.save_overload is caching.Cache.save_overload


def test_a_compile_writes_its_cache_through_the_replaced_method(tmp_path, monkeypatch):
    calls = []
    replaced = caching.Cache.save_overload

    def counting(self, sig, data):
        calls.append(sig)
        return replaced(self, sig, data)

    monkeypatch.setattr(caching.Cache, "save_overload", counting)
    (tmp_path / "rodjit_guard_probe.py").write_text(
        "import numba\n\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2 * x\n")
    sys.path.insert(0, str(tmp_path))
    try:
        module = importlib.import_module("rodjit_guard_probe")
    finally:
        sys.path.remove(str(tmp_path))
    assert module.twice(21) == 42
    assert len(calls) == 1
