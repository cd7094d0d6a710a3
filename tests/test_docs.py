"""The documentation: the built site covers every public module and CLI verb, the
configuration reference every key with its unit and range, every public callable documents
its parameters (numpydoc), and the verification figures are made by the script."""
from __future__ import annotations

import importlib
import importlib.util
import inspect
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

import rodjit
from rodjit import config
from rodjit.cli import main as cli_main

ROOT = Path(__file__).resolve().parents[1]


def _load(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


generate = _load(ROOT / "docs" / "hooks" / "generate.py", "docs_generate")


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    for tool in ("mkdocs", "mkdocstrings", "mkdocs_click", "material", "pymdownx"):
        pytest.importorskip(tool, reason="the docs extra is not installed (pip install -e '.[docs]')")
    out = tmp_path_factory.mktemp("site")
    # Without -q: mkdocs counts a warning against --strict only when it is logged, and -q
    # silences the logging (a build with warnings exits 0 under -q).
    proc = subprocess.run(MKDOCS_BUILD + ["-d", str(out)],
                          cwd=ROOT, capture_output=True, text=True, timeout=900,
                          env={**__import__("os").environ, "NO_MKDOCS_2_WARNING": "1"})
    log = proc.stdout + proc.stderr
    assert proc.returncode == 0, log[-3000:]
    assert not re.search(r"^(WARNING|ERROR)\b", log, re.M), log[-3000:]
    return out


MKDOCS_BUILD = [sys.executable, "-m", "mkdocs", "build", "--strict"]


def test_docs_build_is_strict_and_not_quiet_here_and_in_ci():
    """The site is built with --strict and without -q (which hides the warnings --strict
    counts), by this test and by CI, and CI installs the docs extra for the suite too, so
    the site tests run there instead of skipping."""
    assert "-q" not in MKDOCS_BUILD and "--quiet" not in MKDOCS_BUILD
    ci = (ROOT / ".ci" / "run").read_text()
    builds = [line for line in ci.splitlines() if "mkdocs build" in line
              and not line.lstrip().startswith("#")]
    assert builds and all("--strict" in b for b in builds)
    assert not any(re.search(r"\s(-q|--quiet)\b", b.split("mkdocs build", 1)[1])
                   for b in builds), builds
    lines = ci.splitlines()
    suite = next(i for i, line in enumerate(lines) if "python3 -m pytest" in line)
    venv = max(i for i, line in enumerate(lines[:suite]) if "-m venv" in line)
    # the extras of each ``pip install -e ".[a,b]"`` between the suite's venv and the suite
    extras = {x.strip() for line in lines[venv:suite] if "pip install" in line
              for group in re.findall(r'"\.\[([^\]]*)\]"', line) for x in group.split(",")}
    assert "docs" in extras, lines[venv:suite + 1]


def test_public_modules_include_every_module_in_all():
    mods = generate.public_modules()
    for name in rodjit.__all__:
        obj = getattr(rodjit, name)
        if inspect.ismodule(obj):
            assert obj.__name__ in mods
    assert "rodjit" in mods


def test_site_has_an_api_page_for_every_public_module_listing_its_names(site):
    for module in generate.public_modules():
        page = site / "reference" / "api" / module / "index.html"
        assert page.is_file(), module
        html = page.read_text()
        mod = importlib.import_module(module)
        names = [n for n in getattr(mod, "__all__", []) if n != "__version__"
                 and not inspect.ismodule(getattr(mod, n))]
        objects = dict(generate.api_objects(module))
        assert names and sorted(objects) == sorted(names), module
        for n in names:
            assert f'id="{objects[n]}"' in html, f"{module}.{n} is not on its API page"


def test_site_has_every_cli_verb(site):
    html = (site / "reference" / "cli" / "index.html").read_text()
    assert cli_main.commands
    for verb, cmd in cli_main.commands.items():
        assert f"rodjit {verb}" in html, verb
        for param in cmd.params:
            for opt in getattr(param, "opts", []):
                if opt.startswith("-"):
                    assert opt in html, f"rodjit {verb} {opt}"


def test_site_has_every_guide_page_and_the_integrator_table(site):
    for page in ("getting-started", "MODEL", "units", "integrators", "output", "plotting",
                 "sweeps", "verification", "performance", "reference/configuration"):
        assert (site / page / "index.html").is_file(), page
    html = (site / "integrators" / "index.html").read_text()
    from rodjit.stepping import registry
    for s in registry.SCHEMES:
        assert f"{s.module}.{s.params}" in html, s.name
    assert "rodjit:integrators" not in html


def test_model_page_renders_its_math_and_the_unit_system_is_written_once(site):
    html = (site / "MODEL" / "index.html").read_text()
    assert html.count('class="arithmatex"') >= 5          # $...$ and $$...$$ of MODEL.md
    assert "$$" not in html and "tex-mml-chtml.js" in html and "mathjax.js" in html
    assert "give every unit as a UDUNITS string" in " ".join(
        (site / "units" / "index.html").read_text().split())
    opening = "The model is written for a rod of natural length 1 and mass 1"
    sources = [p for p in (ROOT / "docs").rglob("*.md") if opening in p.read_text()]
    assert sources == [ROOT / "docs" / "MODEL.md"]


def test_configuration_reference_lists_every_key_with_range_default_and_unit():
    page = generate.configuration_page()
    rows = {line.split("|")[1].strip(): line for line in page.splitlines()
            if line.startswith("| `")}
    keys = config.valid_keys()
    assert len(keys) > 20
    for key in keys:
        section, name = key.split(".")
        spec = config._FIELDS[section][name]
        line = rows[f"`{key}`"]
        assert spec.describe().replace("|", "\\|") in line, key
        default = getattr(config._SECTIONS[section](), name)
        assert (f"`{default!r}`" if isinstance(default, str) else
                "unset" if default is None else f"`{default}`") in line, key
        unit = getattr(spec, "unit", None)
        cells = [c.strip() for c in line.split("|")]
        assert cells[3] == (("1 (dimensionless)" if unit == "1" else f"`{unit}`")
                            if unit else "—"), key
        meaning = getattr(spec, "meaning", None)
        if meaning:
            assert meaning in line, key


_SECTION_RULE = re.compile(r"^(\w[\w ]*)\n-{3,}$", re.M)


def _sections(doc: str) -> dict[str, str]:
    """numpydoc sections of a docstring: title -> body."""
    marks = list(_SECTION_RULE.finditer(doc))
    return {m.group(1): doc[m.end():marks[i + 1].start() if i + 1 < len(marks) else None]
            for i, m in enumerate(marks)}


def _documented_names(doc: str) -> set[str]:
    """Names described in the Parameters (or, for a class, Attributes) section: the
    unindented ``name : type`` / ``a, b : type`` lines."""
    sections = _sections(doc)
    body = sections.get("Parameters", "") + sections.get("Attributes", "")
    names = set()
    for line in body.splitlines():
        if line and not line[0].isspace():
            names.update(n.strip().lstrip("*") for n in line.split(" : ")[0].split(","))
    return names


def _parameters(obj) -> list[str]:
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    return [p.name for p in sig.parameters.values()
            if p.name not in ("self", "cls") and not p.name.startswith("_")
            and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]


def _public_callables():
    """``(qualified name, object)`` of every public callable: the names in the ``__all__``
    of every module with an API page, and the public methods and properties of the public
    classes among them."""
    seen = set()
    for module in generate.public_modules():
        mod = importlib.import_module(module)
        for name in getattr(mod, "__all__", []):
            obj = getattr(mod, name)
            if inspect.ismodule(obj) or not callable(obj) or id(obj) in seen:
                continue
            seen.add(id(obj))
            yield f"{module}.{name}", obj
            if not inspect.isclass(obj):
                continue
            for member, attr in vars(obj).items():
                if member.startswith("_"):
                    continue
                if isinstance(attr, (staticmethod, classmethod)):
                    attr = attr.__func__
                if isinstance(attr, property) or inspect.isfunction(attr):
                    yield f"{module}.{name}.{member}", attr


def test_public_callables_cover_modules_and_methods():
    names = {n for n, _ in _public_callables()}
    for expected in ("rodjit.Config", "rodjit.Config.override", "rodjit.SweepTable.to_xarray",
                     "rodjit.Result.n_bounces", "rodjit.laws.register",
                     "rodjit.analysis.first_impact", "rodjit.sweeps.Grid.config",
                     "rodjit.plotting.figure", "rodjit.presets.preset_path"):
        assert expected in names, expected


def test_documented_names_reads_numpydoc_parameter_lines():
    doc = inspect.cleandoc("""What it does.

        Parameters
        ----------
        a, b : float
            The ends.
        **options
            Passed on.

        Returns
        -------
        c : float
            Not a parameter.
        """)
    assert _documented_names(doc) == {"a", "b", "options"}


def test_every_public_callable_documents_its_parameters():
    missing = []
    for name, obj in _public_callables():
        doc = inspect.getdoc(obj.fget if isinstance(obj, property) else obj) or ""
        if not doc.strip():
            missing.append(f"{name}: no docstring")
            continue
        if isinstance(obj, property):
            continue
        params = _parameters(obj)
        if not params:
            continue
        if not _sections(doc).keys() & {"Parameters", "Attributes"}:
            missing.append(f"{name}: no Parameters section for {params}")
            continue
        undocumented = [p for p in params if p not in _documented_names(doc)]
        if undocumented:
            missing.append(f"{name}: parameters {undocumented} not in its Parameters section")
    assert not missing, "\n".join(missing)


# A figure measured against a solution of SciPy's Radau quotes differences that hold only
# to that reference's own error, which the figure measures too (the key here, the motion of
# the reference between two tolerances): it sits at rounding level and follows the
# machine's LAPACK and BLAS.  Its numbers are compared to within that motion, and the
# motion itself to its order of magnitude.
REFERENCE_MOTION = {"scipy_reference.png": "radau_rtol_1e-9_vs_1e-10"}


def _same_measurement(name, key, value, fresh, stored):
    motion_key = REFERENCE_MOTION.get(name)
    if motion_key is None:
        return value == pytest.approx(stored[key], rel=1e-3, abs=1e-12)
    if key == motion_key:
        return stored[key] / 10.0 <= value <= 10.0 * stored[key]
    return value == pytest.approx(stored[key], rel=1e-3,
                                  abs=max(fresh[motion_key], stored[motion_key]))


@pytest.mark.slow
def test_verification_figures_are_made_by_the_script(tmp_path):
    """The script makes every committed figure and the numbers the page quotes; the
    committed numbers are the ones a fresh run measures (to rounding across machines, or
    to the reference's own motion where a figure is measured against SciPy's Radau)."""
    pytest.importorskip("matplotlib")
    proc = subprocess.run([sys.executable, str(ROOT / "docs" / "scripts" / "verification.py"),
                           str(tmp_path)], capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    committed = ROOT / "docs" / "figures"
    made = sorted(p.name for p in tmp_path.glob("*.png"))
    assert made == sorted(p.name for p in committed.glob("*.png"))
    page = (ROOT / "docs" / "verification.md").read_text()
    for name in made:
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"figures/{name}" in page
    fresh = json.loads((tmp_path / "verification.json").read_text())
    stored = json.loads((committed / "verification.json").read_text())
    assert sorted(fresh) == sorted(stored) and len(fresh) >= 4
    for name, entry in fresh.items():
        assert f"<!-- rodjit:measured {name} -->" in page, name
        assert sorted(entry["numbers"]) == sorted(stored[name]["numbers"]), name
        for key, value in entry["numbers"].items():
            assert math.isfinite(value), (name, key)
            assert _same_measurement(name, key, value, entry["numbers"],
                                     stored[name]["numbers"]), \
                f"{name} {key}: rerun docs/scripts/verification.py docs/figures"
    assert set(generate.MEASURED_MARKER.findall(page)) == set(fresh)


def test_measured_markers_become_the_captions_of_the_committed_numbers():
    stored = json.loads((ROOT / "docs" / "figures" / "verification.json").read_text())
    page = (ROOT / "docs" / "verification.md").read_text()
    out = generate.on_page_markdown(page, None, None, None)
    assert "rodjit:measured" not in out
    for entry in stored.values():
        assert entry["caption"] in out
    with pytest.raises(KeyError, match="no numbers for nothing.png"):
        generate.measured_caption("nothing.png")


def test_reference_measurements_are_compared_to_the_references_motion():
    """A figure against SciPy's Radau tolerates the reference's motion and no more; the
    motion itself its order of magnitude; every other figure rounding."""
    stored = {"radau_rtol_1e-9_vs_1e-10": 1.0e-11, "dp54_max_abs_u": 7.0e-10}
    fresh = {"radau_rtol_1e-9_vs_1e-10": 3.0e-12, "dp54_max_abs_u": 7.09e-10}
    ok = lambda key, value: _same_measurement("scipy_reference.png", key, value, fresh, stored)
    assert ok("radau_rtol_1e-9_vs_1e-10", 3.0e-12)
    assert not ok("radau_rtol_1e-9_vs_1e-10", 5.0e-13)
    assert ok("dp54_max_abs_u", 7.09e-10)
    assert not ok("dp54_max_abs_u", 7.2e-10)
    assert _same_measurement("modes.png", "order_k1", 2.0035, {}, {"order_k1": 2.0036})
    assert not _same_measurement("modes.png", "order_k1", 2.01, {}, {"order_k1": 2.0036})
