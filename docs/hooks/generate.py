"""MkDocs hook: the pages that are made from the code at build time.

Generated (never written into ``docs/``, so they cannot go stale in the repository):

- ``reference/configuration.md``: every key of ``rodjit.config._FIELDS`` with its type and
  range (``_Spec.describe()``), its default (from the section dataclasses) and, where the
  spec declares them, its meaning and unit;
- ``reference/api/<module>.md``: one mkdocstrings page per public module (``PUBLIC_MODULES``
  plus every module named in ``rodjit.__all__``);
- in any page, the marker ``<!-- rodjit:integrators -->`` becomes the table of the
  integrators registered in ``rodjit.stepping.registry``.

The command-line reference is ``reference/cli.md``: mkdocs-click renders every verb of
``rodjit.cli:main`` from the click commands.
"""
from __future__ import annotations

import dataclasses
import importlib
import inspect
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[2]

# The modules a user imports; each gets an API page.  Modules named in rodjit.__all__ are
# added automatically (public_modules()).
PUBLIC_MODULES = ["rodjit", "rodjit.config", "rodjit.laws", "rodjit.analysis",
                  "rodjit.sweeps", "rodjit.plotting", "rodjit.presets"]

INTEGRATOR_MARKER = "<!-- rodjit:integrators -->"


def public_modules() -> list[str]:
    import rodjit
    names = list(PUBLIC_MODULES)
    for n in rodjit.__all__:
        obj = getattr(rodjit, n)
        if inspect.ismodule(obj) and obj.__name__ not in names:
            names.append(obj.__name__)
    return names


def api_page(module: str) -> str:
    mod = importlib.import_module(module)
    summary = (inspect.getdoc(mod) or "").split("\n\n")[0]
    if module == "rodjit":
        body = ["# `rodjit`", "", summary, "",
                "The names below are `rodjit.__all__`, the package's public interface.", ""]
        import rodjit
        for n in rodjit.__all__:
            obj = getattr(rodjit, n)
            if inspect.ismodule(obj):
                body += [f"- [`rodjit.{n}`]({obj.__name__}.md) (module)"]
        body += ["", "::: rodjit", "    options:",
                 "      members: " + repr([n for n in rodjit.__all__
                                           if not inspect.ismodule(getattr(rodjit, n))
                                           and n != "__version__"]),
                 "      show_root_heading: false", ""]
        return "\n".join(body)
    return "\n".join([f"# `{module}`", "", f"::: {module}", "    options:",
                      "      show_root_heading: false", ""])


def _fmt_default(value) -> str:
    if value is None:
        return "unset"
    return f"`{value!r}`" if isinstance(value, str) else f"`{value}`"


def config_rows() -> list[dict]:
    """One dict per configuration key: key, type/range, default, meaning, unit."""
    from rodjit import config
    rows = []
    for section, fields in config._FIELDS.items():
        cls = config._SECTIONS[section]
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
                "section_doc": inspect.getdoc(cls) or "",
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
        unit = f"`{r['unit']}`" if r["unit"] else "—"
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


def on_page_markdown(markdown, page, config, files):
    if INTEGRATOR_MARKER in markdown:
        markdown = markdown.replace(INTEGRATOR_MARKER, integrator_table())
    return markdown
