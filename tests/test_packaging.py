"""The install ships every subpackage, the presets, the console script and lean runtime deps."""
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_every_subpackage_is_listed():
    found = {".".join(p.parent.relative_to(ROOT).parts)      # namespace dirs count too
             for p in (ROOT / "rodjit").rglob("*.py") if "__pycache__" not in p.parts}
    listed = set(PYPROJECT["tool"]["setuptools"]["packages"])
    assert found | {"rodjit.data"} == listed


def test_presets_are_package_data():
    tool = PYPROJECT["tool"]["setuptools"]
    assert tool["package-dir"]["rodjit.data"] == "data"
    assert tool["package-data"]["rodjit.data"] == ["*.toml"]
    assert (ROOT / "data" / "__init__.py").exists()
    assert {p.name for p in (ROOT / "data").glob("*.toml")} >= {"paper_mu0.toml",
                                                                "paper_mu100.toml"}


def test_console_script_and_dependencies():
    project = PYPROJECT["project"]
    assert project["scripts"] == {"rodjit": "rodjit.entry:main"}
    runtime = {d.split(">")[0].split("=")[0].strip() for d in project["dependencies"]}
    assert runtime == {"numpy", "numba", "h5py", "click", "tqdm"}
    extras = project["optional-dependencies"]
    test = " ".join(extras["test"])
    for name in ("xarray", "h5netcdf", "psutil", "rodjit[plot]"):
        assert name in test
    assert any(d.startswith("matplotlib") for d in extras["plot"])
    assert {d.split(">")[0] for d in extras["analysis"]} == {"xarray", "h5netcdf", "pandas"}
    # [all]: every extra a user runs rodjit with; the developers' extras (tests, the
    # documentation build, the benchmark peers) stay apart, and so does the GPU engine's
    # (numba-cuda with the CUDA 12 compiler: for NVIDIA machines only, hundreds of MB)
    assert set(extras["all"]) == {f"rodjit[{name}]" for name in extras
                                  if name not in ("all", "test", "docs", "bench", "cuda")}
    assert [d.split(">")[0] for d in extras["cuda"]] == ["numba-cuda[cu12]"]


def test_ci_runs_exactly_the_readme_test_command():
    readme = (ROOT / "README.md").read_text().splitlines()
    commands = [line for line in readme[:8] if "pip install" in line]
    assert len(commands) == 2
    test_command = commands[1].strip()
    assert "pytest" in test_command
    assert test_command in (ROOT / ".ci" / "run").read_text()
