"""What a user installs is described truthfully: license, citation, changelog, classifiers,
and lower bounds that match the minimum versions .ci/run installs and smoke-tests."""
import importlib.util
import re
import tomllib
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
PAPER_TITLE = "New approach for elastic collisions with singular stress functions"
ARXIV_ID = "2601.02639"


def _min_constraints():
    spec = importlib.util.spec_from_file_location("min_constraints",
                                                  ROOT / ".ci" / "min_constraints.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_license_file_and_spdx_expression():
    project = PYPROJECT["project"]
    assert project["license"] == "MIT"
    assert project["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License\n")
    assert re.search(r"^Copyright \(c\) \d{4} rodjit developers$", text, re.M)
    # PEP 639: the expression replaces license classifiers (setuptools refuses both).
    assert not [c for c in project["classifiers"] if c.startswith("License ::")]
    setuptools_req = [r for r in PYPROJECT["build-system"]["requires"]
                      if r.startswith("setuptools")]
    assert setuptools_req == ["setuptools>=77"]     # the first with PEP 639 metadata


def test_python_classifiers_start_at_requires_python():
    project = PYPROJECT["project"]
    versions = sorted(tuple(map(int, c.rsplit(" ", 1)[1].split(".")))
                      for c in project["classifiers"]
                      if re.fullmatch(r"Programming Language :: Python :: 3\.\d+", c))
    assert versions, "no Python version classifiers"
    assert project["requires-python"] == ">={}.{}".format(*versions[0])
    assert versions == [(3, m) for m in range(versions[0][1], versions[-1][1] + 1)]


def test_citation_cff_cites_the_paper_and_rodjit():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0"
    assert cff["type"] == "software"
    assert "rodjit" in cff["title"]
    assert cff["version"] == PYPROJECT["project"]["version"]
    assert cff["license"] == PYPROJECT["project"]["license"]
    assert cff["message"] and cff["authors"]
    paper = cff["preferred-citation"]
    assert paper["title"] == PAPER_TITLE
    assert PAPER_TITLE in " ".join((ROOT / "README.md").read_text().split())
    assert [a["family-names"] for a in paper["authors"]] == ["Aiki", "Kosugi"]
    assert ARXIV_ID in paper["url"]
    assert {"type": "other", "value": f"arXiv:{ARXIV_ID}"}.items() <= paper["identifiers"][0].items()


def test_changelog_has_unreleased_and_current_version():
    text = (ROOT / "CHANGELOG.md").read_text()
    headings = re.findall(r"^## \[([^\]]+)\]", text, re.M)
    assert headings[0] == "Unreleased"
    assert PYPROJECT["project"]["version"] in headings


def test_min_constraints_match_pyproject_lower_bounds():
    mc = _min_constraints()
    written = (ROOT / ".ci" / "min-constraints.txt").read_text()
    assert written == mc.render(PYPROJECT), "run `python3 .ci/min_constraints.py --write`"
    pins = dict(line.split("==") for line in written.splitlines() if not line.startswith("#"))
    for req in PYPROJECT["project"]["dependencies"]:
        name, bound = re.split(r"\s*>=\s*", req)
        assert pins[name] == bound
    assert pins["llvmlite"] == "0.{}".format(int(pins["numba"].split(".")[1]) - 17)
    for extra in mc.EXTRAS:
        for req in PYPROJECT["project"]["optional-dependencies"][extra]:
            name = req.split("[")[0].split(">=")[0]
            assert name in pins, f"extra {extra}: {name} has no pinned minimum"


def test_min_constraints_refuse_a_dependency_without_lower_bound():
    mc = _min_constraints()
    project = {"name": "rodjit", "dependencies": ["numpy>=1.24", "click"],
               "optional-dependencies": {e: [] for e in mc.EXTRAS}}
    with pytest.raises(ValueError, match="'click' needs a single lower bound"):
        mc.lower_bounds({"project": project})
    project["dependencies"] = ["numpy>=1.24,<3"]
    with pytest.raises(ValueError, match="numpy"):
        mc.lower_bounds({"project": project})
    project["dependencies"] = ["numpy>=1.24", "numba>=0.62"]
    project["optional-dependencies"]["plot"] = ["matplotlib>=3.7", "rodjit[dask]"]
    assert mc.lower_bounds({"project": project}) == {
        "numpy": "1.24", "numba": "0.62", "llvmlite": "0.45", "matplotlib": "3.7"}
