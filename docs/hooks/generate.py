"""MkDocs hook: the pages that are made from the code at build time.

Generated (never written into ``docs/``, so they cannot go stale in the repository):

- ``reference/configuration.md``: every key of ``rodjit.config.FIELDS`` with its type and
  range (``KeySpec.describe()``), its default (from the section dataclasses) and, where the
  spec declares them, its meaning and unit;
- ``reference/api/<module>.md``: one mkdocstrings page per public module (``PUBLIC_MODULES``
  plus every module named in ``rodjit.__all__``);
- in any page, the marker ``<!-- rodjit:integrators -->`` becomes the table of the
  integrators registered in ``rodjit.stepping.registry``, and ``<!-- rodjit:measured
  NAME.png -->`` the caption ``docs/scripts/verification.py`` wrote for figure NAME.png
  into ``docs/figures/verification.json`` (the numbers that figure measures).

The command-line reference is ``reference/cli.md``: mkdocs-click renders every verb of
``rodjit.cli:main`` from the click commands.
"""
from __future__ import annotations

import dataclasses
import importlib
import inspect
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# The modules a user imports; each gets an API page.  Modules named in rodjit.__all__ are
# added automatically (public_modules()).
PUBLIC_MODULES = ["rodjit", "rodjit.config", "rodjit.laws", "rodjit.observers",
                  "rodjit.analysis", "rodjit.sweeps", "rodjit.plotting", "rodjit.presets"]

INTEGRATOR_MARKER = "<!-- rodjit:integrators -->"
MEASURED_MARKER = re.compile(r"<!-- rodjit:measured (\S+) -->")
MEASURED_FILE = ROOT / "docs" / "figures" / "verification.json"


def public_modules() -> list[str]:
    import rodjit
    names = list(PUBLIC_MODULES)
    for n in rodjit.__all__:
        obj = getattr(rodjit, n)
        if inspect.ismodule(obj) and obj.__name__ not in names:
            names.append(obj.__name__)
    return names


def _defined_in_source(module: str, name: str) -> bool:
    """Whether ``def name``/``class name`` is written in the file of ``module`` in rodjit
    (not made at run time, not from a dependency), so mkdocstrings can find it there."""
    file = getattr(sys.modules.get(module), "__file__", None)
    stem = ROOT.joinpath(*module.split("."))
    if not file or Path(file).resolve() not in (stem.with_suffix(".py"), stem / "__init__.py"):
        return False
    text = Path(file).read_text()
    return f"def {name}(" in text or f"class {name}(" in text or f"class {name}:" in text


def api_objects(module: str) -> list[tuple[str, str]]:
    """``(public name, path of its definition)`` for each name in the module's ``__all__``.

    Functions and classes are documented where they are defined (a package may re-export
    the function ``converge`` of its submodule ``converge``; the definition's path is
    unambiguous); constants under the module that exports them.
    """
    mod = importlib.import_module(module)
    out = []
    for n in getattr(mod, "__all__", []):
        obj = getattr(mod, n)
        if inspect.ismodule(obj) or n == "__version__":
            continue
        defined = getattr(obj, "__module__", None)
        qual = getattr(obj, "__qualname__", None)
        if ((inspect.isclass(obj) or inspect.isfunction(obj)) and defined and qual
                and "<locals>" not in qual and _defined_in_source(defined, qual)):
            out.append((n, f"{defined}.{qual}"))
        else:
            out.append((n, f"{module}.{n}"))
    return out


def api_page(module: str) -> str:
    mod = importlib.import_module(module)
    doc = inspect.getdoc(mod) or ""
    body = [f"# `{module}`", "", doc, ""]
    subs = [getattr(mod, n).__name__ for n in getattr(mod, "__all__", [])
            if inspect.ismodule(getattr(mod, n))]
    if subs:
        body += ["Modules: " + ", ".join(f"[`{m}`]({m}.md)" for m in subs), ""]
    for name, path in api_objects(module):
        body += [f"::: {path}", "    options:", "      show_root_heading: true",
                 "      show_root_full_path: false", "      heading_level: 2", ""]
    return "\n".join(body)


def _fmt_default(value) -> str:
    if value is None:
        return "unset"
    return f"`{value!r}`" if isinstance(value, str) else f"`{value}`"


def config_rows() -> list[dict]:
    """One dict per configuration key: key, type/range, default, meaning, unit."""
    from rodjit import config
    rows = []
    for section, fields in config.FIELDS.items():
        cls = config.SECTIONS[section]
        defaults = {f.name: (f.default if f.default is not dataclasses.MISSING
                             else f.default_factory())
                    for f in dataclasses.fields(cls)}
        for name, spec in fields.items():
            rows.append({
                "key": f"{section}.{name}",
                "range": spec.describe(),
                "default": _fmt_default(defaults.get(name)),
                "meaning": getattr(spec, "meaning", None) or "",
                "unit": getattr(spec, "unit", None) or "",
                "section": section,
                # the section's own words: its Parameters are this table
                "section_doc": (inspect.getdoc(cls) or "").split("\n\nParameters\n")[0],
            })
    return rows


def configuration_page() -> str:
    from rodjit.records.metadata import UNIT_SYSTEM
    rows = config_rows()
    out = ["# Configuration reference", "",
           "Generated from the field specifications in `rodjit/config.py` when the site is "
           "built: every key a TOML file, `--set key=value`, `--grid` or "
           "`Config.override` accepts.", "",
           f"Units: {UNIT_SYSTEM}. See [Units](../units.md).", "",
           "A configuration file names any subset of the keys; the rest keep their defaults:",
           "", "```toml", "[rod]", "mu = 100.0", "", "[time]", "t_end = 2.0", "```", ""]
    section = None
    for r in rows:
        if r["section"] != section:
            section = r["section"]
            out += ["", f"## `[{section}]`", "", r["section_doc"], "",
                    "| key | meaning | unit | type and range | default |",
                    "|---|---|---|---|---|"]
        unit = ("1 (dimensionless)" if r["unit"] == "1" else f"`{r['unit']}`") if r["unit"] else "—"
        rng = r["range"].replace("|", "\\|")
        out.append(f"| `{r['key']}` | {r['meaning'] or '—'} | {unit} | {rng} | {r['default']} |")
    return "\n".join(out) + "\n"


def integrator_table() -> str:
    from rodjit.stepping import registry
    out = ["| `time.integrator` | parameters | implementation | what it is |", "|---|---|---|---|"]
    for s in registry.SCHEMES:
        mod = importlib.import_module(s.module)
        params = getattr(mod, s.params)
        fields = ", ".join(f"`{f}`" for f in getattr(params, "_fields", ()))
        doc = (inspect.getdoc(mod) or "").split("\n\n")[0].replace("\n", " ").replace("|", "\\|")
        out.append(f"| `{s.name}` | {fields} | `{s.module}.{s.params}` | {doc} |")
    return "\n".join(out)


def on_files(files, config):
    from mkdocs.structure.files import File
    files.append(File.generated(config, "reference/configuration.md",
                                content=configuration_page()))
    for module in public_modules():
        files.append(File.generated(config, f"reference/api/{module}.md",
                                    content=api_page(module)))
    return files


def on_config(config):
    """Replace the nav's ``Python API`` entry by one page per public module."""
    def fill(items):
        for i, item in enumerate(items):
            if isinstance(item, dict):
                (title, value), = item.items()
                if title == "Python API":
                    items[i] = {title: [{m: f"reference/api/{m}.md"} for m in public_modules()]}
                elif isinstance(value, list):
                    fill(value)
    fill(config["nav"])
    return config


def measured_caption(figure: str) -> str:
    """The caption of a verification figure, with the numbers it measured."""
    measured = json.loads(MEASURED_FILE.read_text())
    if figure not in measured:
        raise KeyError(f"{MEASURED_FILE.name} has no numbers for {figure}: run "
                       f"docs/scripts/verification.py docs/figures")
    return measured[figure]["caption"]


def on_page_markdown(markdown, page, config, files):
    if INTEGRATOR_MARKER in markdown:
        markdown = markdown.replace(INTEGRATOR_MARKER, integrator_table())
    return MEASURED_MARKER.sub(lambda m: measured_caption(m.group(1)), markdown)
