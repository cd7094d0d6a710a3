"""The package's names load on first use (``rodjit._lazy``): ``import rodjit``, the command
line's help and a sweep worker running batches import only what their work needs, and every
public name still reads as the object of its module."""
import ast
import importlib
import importlib.util
import inspect
import os
import subprocess
import sys
import textwrap

import pytest

import rodjit
import rodjit.sweeps
from rodjit import _lazy


def _python(code: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args, "-c", textwrap.dedent(code)],
                          capture_output=True, text=True, timeout=600, env=dict(os.environ))


def _loaded(code: str) -> set[str]:
    """The top-level packages a fresh interpreter has loaded after ``code``."""
    done = _python(textwrap.dedent(code) + "\nimport sys\nprint(' '.join(sorted(sys.modules)))\n")
    assert done.returncode == 0, done.stderr
    return set(done.stdout.split())


@pytest.mark.parametrize("package", [rodjit, rodjit.sweeps])
def test_every_public_name_is_its_modules_object(package):
    for name in package.__all__:
        source = importlib.import_module(package._WHERE[name], package.__name__)
        own = source.__name__ == f"{package.__name__}.{name}"    # the name is the module
        expected = source if own else getattr(source, name)
        assert getattr(package, name) is expected, name
        assert name in dir(package)


def test_star_import_and_subpackages_are_attributes():
    namespace: dict = {}
    exec("from rodjit import *", namespace)
    assert namespace["Config"] is rodjit.Config and namespace["sweep"] is rodjit.sweeps.sweep
    # rodjit's subpackages, and rodjit.sweeps' modules, are attributes on first use
    code = """
        import rodjit
        assert callable(rodjit.analysis.first_impact)
        assert rodjit.sweeps.grid.Grid is rodjit.sweeps.Grid
        print("ok")
        """
    done = _python(code)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        rodjit.no_such_name
    with pytest.raises(AttributeError, match="no attribute '__wrapped__'"):
        rodjit.__wrapped__
    assert not hasattr(rodjit.sweeps, "no_such_name")


def test_a_submodule_that_fails_to_import_says_why(tmp_path, monkeypatch):
    """A submodule whose own import fails raises that error, not 'no attribute'."""
    pkg = tmp_path / "lazy_probe_pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "broken.py").write_text("import lazy_probe_missing_dependency\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ModuleNotFoundError, match="lazy_probe_missing_dependency"):
        _lazy.attribute("lazy_probe_pkg", {}, "broken")
    with pytest.raises(AttributeError):
        _lazy.attribute("lazy_probe_pkg", {}, "absent")


def test_import_rodjit_loads_no_numerics():
    loaded = _loaded("import rodjit")
    assert not loaded & {"numpy", "h5py", "numba", "click"}, loaded & {"numpy", "h5py"}


def test_the_commands_help_loads_no_numerics():
    done = _python("import sys; sys.argv = ['rodjit', '--help']\n"
                   "from rodjit.entry import main\nmain()", "-X", "importtime")
    assert done.returncode == 0 and "Usage: rodjit" in done.stdout, done.stderr
    modules = {line.rsplit("|", 1)[-1].strip() for line in done.stderr.splitlines()}
    assert "click" in modules and not modules & {"numpy", "h5py", "numba"}


def test_a_batch_worker_loads_no_run_file_writer():
    """A pool worker of the ensemble engine (its module, then a batch run) loads neither
    h5py nor the run files' writer, which only ``--save-runs`` points use."""
    loaded = _loaded("""
        import numpy as np
        from rodjit.sweeps import pool
        from rodjit.config import Config
        from rodjit.sweeps.ensemble import BatchTask, run_batch
        from rodjit.sweeps.grid import Grid
        base = Config().override({"time.t_end": 0.05})
        result = run_batch(BatchTask(np.arange(2), base, Grid.from_spec({"rod.mu": [0, 50]}), ()))
        assert list(result.values["status"]) == ["completed", "completed"], result.values
        """)
    assert "rodjit.sweeps.ensemble" in loaded
    assert not loaded & {"h5py", "rodjit.driver.files", "rodjit.output.run_writer",
                         "rodjit.plotting.dispatch", "rodjit.analysis"}


@pytest.mark.parametrize("package", [rodjit, rodjit.sweeps])
def test_the_names_static_tools_see_are_the_lazy_ones(package):
    """The imports under ``TYPE_CHECKING`` (what mypy and editors read) name exactly the
    lazy names, each from the module ``_WHERE`` loads it from."""
    tree = ast.parse(inspect.getsource(package))
    block = next(node for node in tree.body if isinstance(node, ast.If)
                 and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING")
    seen = {}
    for node in block.body:
        assert isinstance(node, ast.ImportFrom), ast.dump(node)
        for alias in node.names:
            module = "." * node.level + (node.module or "")
            full = importlib.util.resolve_name(module, package.__name__)
            seen[alias.asname or alias.name] = full
    expected = {}
    for name, where in package._WHERE.items():
        full = importlib.util.resolve_name(where, package.__name__)
        module = importlib.import_module(full)
        # a name imported from a submodule of its module (``.analysis.fit``) is the same
        # object: compare the objects
        expected[name] = module if full == f"{package.__name__}.{name}" else getattr(module, name)
    assert set(seen) == set(expected)
    for name, full in seen.items():
        module = importlib.import_module(full)
        got = module if full == f"{package.__name__}.{name}" else getattr(module, name)
        assert got is expected[name], name
