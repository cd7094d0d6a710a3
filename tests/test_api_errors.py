"""Errors of the Python API name the argument: a profile of non-numbers, a height the node
spacing cannot survive."""
from __future__ import annotations

import pytest

import rodjit

SHORT = rodjit.Config().override({"time.t_end": 0.01})


@pytest.mark.parametrize("u0", [["a"] * 6, [[1.0, 2.0], [3.0]], [object()] * 6])
def test_a_profile_of_non_numbers_is_named(u0):
    with pytest.raises(ValueError, match=r"^u0 must be an array of numbers of length"):
        rodjit.simulate(SHORT, u0=u0)


def test_a_huge_initial_height_is_named_with_its_range():
    with pytest.raises(ValueError, match=r"^initial.height = 1000000000000.0 is out of range"):
        rodjit.simulate(SHORT.override({"initial.height": 1e12}))
    assert rodjit.simulate(SHORT.override({"initial.height": 10.0})).t[-1] > 0


@pytest.mark.parametrize("read", [rodjit.open_run, rodjit.load_file, rodjit.load_sweep,
                                  rodjit.Config.from_toml],
                         ids=["open_run", "load_file", "load_sweep", "Config.from_toml"])
def test_a_missing_file_is_a_file_not_found_error(read, tmp_path):
    """What ``open`` raises, and still the ValueError the command line words in one line
    (exit 2); its errno and filename are those of a FileNotFoundError."""
    import errno
    import pickle

    path = tmp_path / "missing.h5"
    with pytest.raises(FileNotFoundError, match=r"'.*missing\.h5' does not exist$") as info:
        read(path)
    exc = info.value
    assert isinstance(exc, ValueError) and isinstance(exc, rodjit.config.MissingFile)
    assert exc.errno == errno.ENOENT and exc.filename == str(path)
    assert str(pickle.loads(pickle.dumps(exc))) == str(exc)
    if getattr(read, "__self__", None) is not rodjit.Config:      # a file rodjit writes
        assert isinstance(exc, rodjit.output.hdf5.NotARunFile)


@pytest.mark.parametrize("changes", [{"time.t_end": 1e300},
                                     {"output.snapshot_interval": 0.0, "time.t_end": 1e5},
                                     {"time.dt": 1e-9, "time.t_end": 100.0,
                                      "output.snapshot_interval": 0.0,
                                      "output.diagnostics_interval": 0.0}],
                         ids=["t_end 1e300", "diagnostics of a long run", "1e11 fixed steps"])
def test_simulate_refuses_what_run_to_file_refuses(changes, tmp_path):
    """``simulate`` and ``run_to_file`` share one size and step estimate
    (``output.estimate.check_run``): what the file writer refuses, the in-memory run
    refuses too, before anything is allocated, with the same limits and their keywords."""
    from rodjit.output.errors import FileTooLarge, TooManySteps

    cfg = rodjit.Config().override(changes)
    with pytest.raises((FileTooLarge, TooManySteps)) as file_refusal:
        rodjit.run_to_file(cfg, tmp_path / "x.h5")
    with pytest.raises(type(file_refusal.value)):
        rodjit.simulate(cfg, progress=_never_called)
    assert list(tmp_path.iterdir()) == []


def _never_called(run):
    raise AssertionError(f"the run started (t = {run.t})")


def test_simulate_takes_the_limits():
    small = SHORT.override({"output.snapshot_interval": 1e-4})
    with pytest.raises(ValueError, match=r"more than the limit of 1 KiB"):
        rodjit.simulate(small, max_output=1024)
    with pytest.raises(ValueError, match=r"needs 1e\+03 steps .* more than the limit of 10"):
        rodjit.simulate(small.override({"time.dt": 1e-5}), max_steps=10)


@pytest.mark.parametrize("limit", [float("nan"), 1.5, 0, -1, True, "many"])
def test_a_limit_that_is_no_limit_is_named(limit, tmp_path):
    """NaN would turn a limit off (every comparison false); a fraction was shown rounded
    ("2 points, more than the limit of 2"): both refused, naming the keyword."""
    from rodjit.sweeps.grid import Grid

    with pytest.raises(ValueError, match=r"^max_points = .* is (out of range|not a number)"):
        Grid.from_spec({"rod.mu": [0.0, 1.0]}, max_points=limit)
    with pytest.raises(ValueError, match=r"^max_points = "):
        rodjit.plan_sweep(SHORT, {"rod.mu": [0.0, 1.0]}, max_points=limit)
    with pytest.raises(ValueError, match=r"^max_steps = "):
        rodjit.run_to_file(SHORT, tmp_path / "x.h5", max_steps=limit)
    with pytest.raises(ValueError, match=r"^max_steps = "):
        rodjit.plan_sweep(SHORT.override({"time.dt": 1e-3}), {"rod.mu": [0.0, 1.0]},
                          max_steps=limit)
    assert list(tmp_path.iterdir()) == []


def test_infinity_is_the_api_s_way_to_lift_a_limit():
    import math

    from rodjit.sweeps.grid import Grid

    assert len(Grid.from_spec({"rod.mu": [0.0, 1.0]}, max_points=math.inf)) == 2
    assert rodjit.simulate(SHORT, max_steps=math.inf, max_output=math.inf).t[-1] > 0


@pytest.mark.parametrize("threads", ["0", "abc", "-1", ""])
def test_a_numba_thread_count_numba_cannot_use_is_named(monkeypatch, threads):
    """What loads Numba (the first compile) checks NUMBA_NUM_THREADS first: Numba's own
    error ("Number of threads specified must be > 0.") did not name the variable."""
    from rodjit._jit import check_numba_environment

    monkeypatch.setenv("NUMBA_NUM_THREADS", threads)
    with pytest.raises(ValueError, match=r"^environment variable NUMBA_NUM_THREADS = "):
        check_numba_environment()
    monkeypatch.setenv("NUMBA_NUM_THREADS", "2")
    check_numba_environment()


@pytest.mark.parametrize("changes", [None, "rod.mu=1", ["rod.mu", 1.0], [("rod.mu", 1.0)], 3],
                         ids=["None", "text", "list", "pairs", "number"])
def test_override_names_its_argument(changes):
    """``override`` of something not a mapping raised an AttributeError about ``.items``."""
    with pytest.raises(TypeError, match=r"^Config\.override\(changes\): changes must be a "
                                        r"mapping of dotted keys to values"):
        rodjit.Config().override(changes)
    assert rodjit.Config().override({"rod.mu": 1.0}).rod.mu == 1.0


def _plain_value(e, p):
    return p.kappa * e


def _law(**changes):
    from typing import NamedTuple

    from rodjit.laws import Law
    from rodjit.model.laws import aiki_kosugi

    class Refused(NamedTuple):
        kappa: float

    parts = dict(name="refused-test", kind="rod", params=Refused,
                 from_config=lambda rod: Refused(float(rod.kappa)),
                 value=aiki_kosugi.rod_value, deriv=aiki_kosugi.rod_deriv,
                 primitive=aiki_kosugi.rod_primitive, lower=aiki_kosugi.rod_lower)
    return Law(**{**parts, **changes})


@pytest.mark.parametrize("law,named", [
    (None, "law must be a rodjit.laws.Law, not None"),
    ("aiki-kosugi", "law must be a rodjit.laws.Law, not 'aiki-kosugi'"),
    (lambda: _law(value=_plain_value), "law.value must be a compiled function"),
    (lambda: _law(lower=None), "law.lower must be a compiled function"),
    (lambda: _law(deriv_max=_plain_value), "law.deriv_max must be a compiled function"),
    (lambda: _law(params=dict), "law.params must be a NamedTuple class"),
    (lambda: _law(from_config=None), "law.from_config must be callable"),
], ids=["None", "a name", "plain value", "no lower", "plain deriv_max", "params dict",
        "from_config None"])
def test_register_refuses_what_is_not_a_law_at_registration(law, named):
    """A law with a plain Python function (or None) was accepted and failed when a run first
    compiled the loop with it; ``register(None)`` raised an AttributeError."""
    from rodjit.laws import law_names, register

    law = law() if callable(law) else law
    with pytest.raises(TypeError, match=rf"^register\(law\): {named}"):
        register(law)
    assert "refused-test" not in law_names("rod")


def test_a_convergence_study_replaces_only_a_convergence_file(tmp_path):
    """``Convergence.save(path, overwrite=True)`` replaced any file with HDF5."""
    import importlib

    from rodjit.output.errors import OutputOtherKind

    cfg = rodjit.Config().override({"time.t_end": 0.05, "rod.mu": 1.0})
    study = rodjit.converge(cfg, {"rod.N": [3, 5]}, also=False, observables=["min_u0"],
                            jobs=1)
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n")
    with pytest.raises(OutputOtherKind, match="'.*notes.txt' is not a rodjit file"):
        study.save(notes, overwrite=True)
    assert notes.read_text() == "my notes\n"
    study.save(tmp_path / "conv.h5")
    study.save(tmp_path / "conv.h5", overwrite=True)
    load = importlib.import_module("rodjit.analysis.converge").load_convergence
    assert load(tmp_path / "conv.h5")["key"] == "rod.N"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["conv.h5", "notes.txt"]
