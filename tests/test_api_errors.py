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
