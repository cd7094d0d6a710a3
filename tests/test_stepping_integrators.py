"""The integrators' layout: one module per integrator under ``stepping/integrators``, none
importing another, what they share below them, and every stepping module short."""
from __future__ import annotations

import ast
from pathlib import Path

import rodjit
from rodjit.stepping import registry

PACKAGE = Path(rodjit.__file__).resolve().parent
INTEGRATORS = "rodjit.stepping.integrators"


def _imports(path: Path, package: str) -> set[str]:
    """The rodjit modules a file imports (``from . import x`` counts as the module x)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")
            if node.level:
                base = base[:len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.add(mod)
            out.update(f"{mod}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


def test_every_registered_integrator_is_a_module_under_integrators():
    modules = {s.module for s in registry.SCHEMES if s.module.startswith("rodjit.")}
    assert modules, "no built-in integrator"
    for m in modules:
        assert m.rpartition(".")[0] == INTEGRATORS, m


def test_no_integrator_module_imports_another():
    modules = {s.module for s in registry.SCHEMES if s.module.startswith(INTEGRATORS)}
    for m in modules:
        path = PACKAGE.parent / (m.replace(".", "/") + ".py")
        # a module's own parts (``erk_tableau``, ``radau_linear``) are not integrators
        others = (modules - {m})
        found = _imports(path, m) & others
        assert not found, f"{m} imports the integrator module(s) {sorted(found)}"
        # nor does it reach one through a part of its own
        for part in _imports(path, m):
            if part.startswith(INTEGRATORS + ".") and part not in modules:
                p = PACKAGE.parent / (part.replace(".", "/") + ".py")
                if p.exists():
                    assert not (_imports(p, part) & others), f"{part} imports {others}"


def test_stepping_modules_are_short():
    for path in sorted((PACKAGE / "stepping").rglob("*.py")):
        n = len(path.read_text().splitlines())
        assert n < 500, f"{path.relative_to(PACKAGE)} has {n} lines"
