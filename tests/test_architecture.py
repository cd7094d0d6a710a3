"""The package's floors: every import (module level or inside a function) goes to the same
floor or one below, and no modules import each other in a circle.

Floors, lowest first (a module's floor is its first name under ``rodjit``):

- ``version``, ``_jit``, ``_display``, ``_extras``, ``_cache_names``, ``_lazy``: no rodjit
  imports (the installed version; the Numba decorators; how objects print in a shell and in
  Jupyter; optional dependencies; placeholder classes of the cache namespaces; a package's
  names loaded on first use);
- ``model``: the stress laws and the rod's discrete system (MODEL.md);
- ``kernels``: compiled forces, energies and banded solvers;
- ``stepping``: the compiled time loop, its schemes and the layout of its arrays;
- ``config``: the user's configuration, checked against the laws and schemes below it;
- ``presets``: named configurations;
- ``records``: what a run produces (columns, ``Sink``, ``Result``, bounce table, stats,
  extremes), shared by every floor above;
- ``output``: the run file (opening, layout, reader, writer) and its summary;
- ``driver``: a run in progress, ``simulate``, streaming a run to a file;
- ``sweeps``, ``gpu``: grids of runs, their executors and the sweep file; the GPU engine
  of sweeps (numba-cuda, optional);
- ``plotting``: figures of run and sweep files;
- ``reports``: what ``rodjit info`` prints of either kind of file;
- ``cli``, ``__main__``, ``entry``: the ``rodjit`` command;
- the package itself (``rodjit/__init__.py``): the public API, importing from every floor.

No module imports a private name (leading underscore) of another, by ``from`` or as an
attribute of a module it imported; private modules (``_jit``, ...) are the package's own.
"""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import rodjit

PACKAGE = Path(rodjit.__file__).resolve().parent

FLOORS = (
    ("version", "_jit", "_display", "_extras", "_cache_names", "_lazy"),
    ("model", "laws"),
    ("kernels",),
    ("stepping", "observers"),
    ("config",),
    ("presets",),
    ("records",),
    ("output",),
    ("driver",),
    ("sweeps", "gpu"),
    ("analysis",),
    ("plotting",),
    ("reports",),
    ("cli", "__main__", "entry"),
    ("",),                     # rodjit/__init__.py
)
FLOOR_OF = {name: level for level, names in enumerate(FLOORS) for name in names}

# import circles that exist for a reason outside these floors' control, each a set of
# modules; none may be added without its reason
KNOWN_CYCLES: tuple[frozenset[str], ...] = ()


def modules() -> dict[str, Path]:
    """Every module of the package: dotted name -> file."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(("rodjit",) + parts)] = path
    return out


def imports(name: str, path: Path, known: dict) -> set[str]:
    """The rodjit modules ``name`` imports anywhere in its file (inside functions too):
    ``from package import module`` counts as the module, ``from module import name`` as
    the module."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                base = ".".join(base + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            targets = []
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                targets.append(sub if sub in known else base)
        else:
            continue
        for target in targets:
            while target and target not in known:      # ``import rodjit.x.y`` etc.
                target = target.rpartition(".")[0]
            if target.startswith("rodjit") and target != name:
                out.add(target)
    return out


def floor(name: str) -> int:
    top = name.split(".")[1] if "." in name else ""
    if top not in FLOOR_OF:
        raise AssertionError(f"module {name} is on no floor: add {top!r} to FLOORS in "
                             f"{Path(__file__).name}")
    return FLOOR_OF[top]


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    known = modules()
    return {name: imports(name, path, known) for name, path in known.items()}


def cycles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(frozenset(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_walk_sees_the_imports_it_checks(graph):
    """The walker resolves relative, absolute and function-level imports."""
    assert "rodjit.records.sink" in graph["rodjit.driver.run"]           # from ..records.sink
    assert "rodjit.sweeps.sweep_file" in graph["rodjit.sweeps.run_sweep"]  # from . import x
    assert "rodjit.model.laws" in graph["rodjit.config.checks"]          # inside a function
    assert "rodjit.reports" in graph["rodjit.cli.info"]                  # inside a command
    assert "rodjit.version" in graph["rodjit"]


def test_every_module_is_on_a_floor(graph):
    for name in graph:
        floor(name)


def test_no_module_imports_from_a_floor_above_its_own(graph):
    wrong = sorted(f"{name} (floor {FLOORS[floor(name)][0] or 'rodjit'}) imports {target} "
                   f"(floor {FLOORS[floor(target)][0] or 'rodjit'})"
                   for name, targets in graph.items() for target in targets
                   if floor(target) > floor(name))
    assert not wrong, "\n".join(wrong)


def test_no_import_circles(graph):
    found = [sorted(c) for c in cycles(graph) if c not in KNOWN_CYCLES]
    assert not found, f"import circles: {found}"


def test_the_cycle_finder_finds_a_circle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [frozenset("abc")]
    assert cycles({"a": {"b"}, "b": set()}) == []


# modules that are built, not written (no .py file to walk): a name of theirs is a module
BUILT_MODULES = frozenset({"rodjit.stepping._aot_loop"})     # stepping.aot's extension

# private names imported across modules today, each to be made public or moved where it
# is shared (this list only shrinks: the test fails on an entry that is gone)
KNOWN_PRIVATE_IMPORTS: frozenset[str] = frozenset()


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_imports(known: dict[str, Path]) -> set[str]:
    """``A imports B._x``: module A takes a private name ``_x`` of another module B, by
    ``from B import _x`` or as the attribute ``B._x`` of a module it imported (private
    modules, ``_jit`` and the like, are the package's own and may be imported)."""
    modules_here = set(known) | BUILT_MODULES
    out = set()
    for name, path in known.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        tree = ast.parse(path.read_text(), str(path))
        bound = {}                      # local name -> the rodjit module it is
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = ".".join(base[:len(base) - (node.level - 1)]
                                    + ([node.module] if node.module else []))
                else:
                    base = node.module or ""
                if not base.startswith("rodjit"):
                    continue
                for alias in node.names:
                    target = f"{base}.{alias.name}"
                    if target in modules_here:
                        bound[alias.asname or alias.name] = target
                    elif _private(alias.name):
                        out.add(f"{name} imports {target}")
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.startswith("rodjit") and alias.asname:
                        bound[alias.asname] = alias.name
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                    and node.value.id in bound and _private(node.attr)
                    and f"{bound[node.value.id]}.{node.attr}" not in modules_here):
                out.add(f"{name} imports {bound[node.value.id]}.{node.attr}")
    return out


def test_no_private_name_is_imported_across_modules():
    found = private_imports(modules())
    assert not found - KNOWN_PRIVATE_IMPORTS, "\n".join(sorted(found - KNOWN_PRIVATE_IMPORTS))
    assert not KNOWN_PRIVATE_IMPORTS - found, ("no longer imported, take off the list: "
                                               f"{sorted(KNOWN_PRIVATE_IMPORTS - found)}")


def test_the_private_name_walk_sees_both_forms(tmp_path):
    pkg = tmp_path / "rodjit"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("_x = 1\n")
    (pkg / "b.py").write_text("from .a import _x\nfrom . import a\ny = a._y\nfrom . import _c\n")
    (pkg / "_c.py").write_text("")
    known = {"rodjit": pkg / "__init__.py", "rodjit.a": pkg / "a.py", "rodjit.b": pkg / "b.py",
             "rodjit._c": pkg / "_c.py"}
    assert private_imports(known) == {"rodjit.b imports rodjit.a._x",
                                      "rodjit.b imports rodjit.a._y"}


# ---- one meaning per name ---------------------------------------------------------------
# Module-level UPPER_CASE names that modules on different floors define, each for its own
# object, read from their own module (or qualified: ``L.F_T``); name -> the modules that
# define it.  None may be added without its reason.
PARALLEL_NAMES: dict[str, frozenset[str]] = {
    # each kind of file has its layout module, with the same words for its own format
    "FORMAT_VERSION": frozenset({"rodjit.output.run_layout", "rodjit.sweeps.sweep_file",
                                 "rodjit.analysis.converge"}),
    "KIND": frozenset({"rodjit.output.run_layout", "rodjit.sweeps.sweep_file"}),
    "READS": frozenset({"rodjit.output.run_layout", "rodjit.sweeps.sweep_file"}),
    "REQUIRED_ATTRS": frozenset({"rodjit.output.run_layout", "rodjit.sweeps.sweep_file"}),
    # public names of long standing, renaming them would break users' imports: a file's
    # statuses (rodjit.output.hdf5.STATUSES) and a first contact's
    # (rodjit.analysis.observables.STATUSES); the samples a plot draws per curve
    # (rodjit.plotting.MAX_POINTS) and the points a sweep grid may have
    "STATUSES": frozenset({"rodjit.output.run_layout", "rodjit.sweeps.sweep_file",
                           "rodjit.records.contacts"}),
    "MAX_POINTS": frozenset({"rodjit.plotting.source", "rodjit.sweeps.grid"}),
}


def definitions(known: dict[str, Path]) -> tuple[dict[str, set[str]], dict[str, dict[str, str]]]:
    """(class name -> the modules defining a class of that name at module level, public
    UPPER_CASE constant -> {module: the source of its value})."""
    classes: dict[str, set[str]] = {}
    constants: dict[str, dict[str, str]] = {}
    for name, path in known.items():
        for node in ast.parse(path.read_text(), str(path)).body:
            if isinstance(node, ast.ClassDef):
                classes.setdefault(node.name, set()).add(name)
            elif isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None:
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for t in targets:
                    if (isinstance(t, ast.Name) and t.id.isupper()
                            and not t.id.startswith("_")):
                        constants.setdefault(t.id, {})[name] = ast.unparse(node.value)
    return classes, constants


def two_meanings(known: dict[str, Path]) -> dict[str, frozenset[str]]:
    """Names with more than one meaning: a class name defined in two modules (a second
    ``Inline``), and a public constant that modules on different floors define with
    different values (two ``FLUSH_INTERVAL``).  Within a floor, parallel modules keep one
    vocabulary on purpose (each integrator's ``SAFETY``, each figure module's ``KINDS``)."""
    classes, constants = definitions(known)
    out = {f"class {c}": frozenset(mods) for c, mods in classes.items() if len(mods) > 1}
    for c, values in constants.items():
        floors = {floor(m) for m in values}
        if len(floors) > 1 and len(set(values.values())) > 1:
            out[c] = frozenset(values)
    return out


def test_no_name_has_two_meanings():
    found = two_meanings(modules())
    unexpected = {k: sorted(v) for k, v in found.items() if PARALLEL_NAMES.get(k) != v}
    assert not unexpected, unexpected
    assert not PARALLEL_NAMES.keys() - found.keys(), (
        f"defined once now, take off the list: {sorted(PARALLEL_NAMES.keys() - found.keys())}")


def test_the_meaning_walk_sees_classes_and_constants(tmp_path):
    pkg = tmp_path / "rodjit"
    for sub in ("driver", "sweeps"):
        (pkg / sub).mkdir(parents=True)
        (pkg / sub / "__init__.py").write_text("")
    (pkg / "__init__.py").write_text("")
    (pkg / "driver" / "files.py").write_text("class Inline:\n    pass\n\n"
                                             "FLUSH_INTERVAL = 2.0\nSAME = 1\n_OWN = 1\n")
    (pkg / "sweeps" / "run.py").write_text("class Inline:\n    pass\n\n"
                                           "FLUSH_INTERVAL = 1.0\nSAME = 1\n_OWN = 2\n")
    (pkg / "sweeps" / "grid.py").write_text("FLUSH_INTERVAL = 1.0\n")
    known = {"rodjit": pkg / "__init__.py", "rodjit.driver": pkg / "driver" / "__init__.py",
             "rodjit.sweeps": pkg / "sweeps" / "__init__.py",
             "rodjit.driver.files": pkg / "driver" / "files.py",
             "rodjit.sweeps.run": pkg / "sweeps" / "run.py",
             "rodjit.sweeps.grid": pkg / "sweeps" / "grid.py"}
    assert two_meanings(known) == {
        "class Inline": frozenset({"rodjit.driver.files", "rodjit.sweeps.run"}),
        "FLUSH_INTERVAL": frozenset({"rodjit.driver.files", "rodjit.sweeps.run",
                                     "rodjit.sweeps.grid"})}


# ---- one implementation of the first-impact observables --------------------------------
FIRST_IMPACT = "rodjit.stepping.impact_stream"
# the modules that fill the first-impact columns (records.impact.IMPACT_COLUMNS) -> the
# module they take them from: the implementation itself, or records.impact, which runs it
# for one run
FIRST_IMPACT_CALLERS = {
    "rodjit.stepping.trajectory": FIRST_IMPACT,             # a sweep point (either engine)
    "rodjit.records.impact": FIRST_IMPACT,                  # one run (ImpactStream)
    "rodjit.records.result": "rodjit.records.impact",       # Result.impact
    "rodjit.output.run_writer": "rodjit.records.impact",    # a run file as it is written
    "rodjit.output.summary": "rodjit.records.impact",       # a run file read back
    "rodjit.sweeps.point": "rodjit.records.impact",         # a sweep point's sink
    "rodjit.sweeps.decode": "rodjit.records.impact",        # either engine's columns
}
# what the implementation computes: the codes and the values of its ``finish``
FIRST_IMPACT_NAMES = ("LIFT_OFF", "OPEN_AT_END", "NO_IMPACT", "UNDEFINED", "OUT_SIZE",
                      "O_RESTITUTION", "O_APEX", "O_CONTACT_TIME", "O_T_IMPACT",
                      "O_W_IMPACT", "O_REBOUND", "O_MIN_U0", "O_EV_IMPACT")


def _calls_of(tree, name: str) -> bool:
    return any(isinstance(node, ast.Call)
               and ((isinstance(node.func, ast.Name) and node.func.id == name)
                    or (isinstance(node.func, ast.Attribute) and node.func.attr == name))
               for node in ast.walk(tree))


def test_the_first_impact_observables_have_one_implementation(graph):
    """One module computes the first-impact observables of a sweep row (either engine), a
    run file's summary and a Result (``stepping.impact_stream``): it alone defines their
    codes and values, every module that fills the first-impact columns takes them from it
    (or from ``records.impact``, which runs it for one run), and a module that names a code
    or a value imports it.  The whole-table NumPy ``first_impact`` (``records.contacts``)
    serves the analysis API (``records.observables.observables``), never a column."""
    known = modules()
    _, constants = definitions(known)
    for name in FIRST_IMPACT_NAMES:
        assert set(constants.get(name, {})) == {FIRST_IMPACT}, name
    for caller, source in FIRST_IMPACT_CALLERS.items():
        assert source in graph[caller], f"{caller} does not import {source}"
    pattern = re.compile(r"\b(" + "|".join(FIRST_IMPACT_NAMES) + r")\b")
    naming = {name for name, path in known.items() if pattern.search(path.read_text())}
    assert naming - {FIRST_IMPACT} <= {name for name in known if FIRST_IMPACT in graph[name]}
    callers = {name for name, path in known.items()
               if _calls_of(ast.parse(path.read_text(), str(path)), "first_impact")}
    assert callers == {"rodjit.records.observables"}, sorted(callers)


# ---- one implementation of the packing of parameter tuples ------------------------------
PACKING = "rodjit.stepping.packing"
# the modules that move a point's parameter tuples into compiled code as a row of doubles,
# each through the packing: the CPU engine's batch kernel, the ahead-of-time extension's
# wrappers, the GPU kernel's source and the GPU engine's rows
PACKING_CALLERS = ("rodjit.stepping.ensemble", "rodjit.stepping.aot", "rodjit.gpu.kernel",
                   "rodjit.gpu.engine")


def field_walkers(known: dict[str, Path]) -> set[str]:
    """Modules that walk the fields of each of several tuples: a loop (or comprehension)
    over the items of the enclosing loop's item (``for t in params: for x in t``), the
    shape of every packing of parameter tuples into a row."""
    out = set()
    for name, path in known.items():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            pairs = []
            if isinstance(node, (ast.ListComp, ast.GeneratorExp, ast.SetComp, ast.DictComp)):
                pairs = [(a.target, b.iter) for a, b in zip(node.generators,
                                                            node.generators[1:])]
            elif isinstance(node, ast.For):
                pairs = [(node.target, inner.iter) for inner in ast.walk(node)
                         if isinstance(inner, ast.For) and inner is not node]
            if any(isinstance(t, ast.Name) and isinstance(i, ast.Name) and i.id == t.id
                   for t, i in pairs):
                out.add(name)
    return out


def rebuild_writers(known: dict[str, Path]) -> set[str]:
    """Modules that write source reading a bool back from a row of doubles: a string
    (or the text of an f-string) holding ``!= 0``, as every generated rebuilding does."""
    out = set()
    for name, path in known.items():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.JoinedStr):
                text = "".join(v.value for v in node.values if isinstance(v, ast.Constant))
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                text = node.value
            else:
                continue
            if re.search(r"!=\s*0", text):
                out.add(name)
    return out


def test_the_packing_of_parameter_tuples_has_one_implementation(graph):
    """One module packs a point's parameter tuples into a row of doubles and writes the
    source that rebuilds them in compiled code (``stepping.packing``); the CPU batch
    kernel, the ahead-of-time wrappers and the GPU kernel all take it from there, and no
    other module walks tuples' fields or writes a rebuilding."""
    known = modules()
    assert field_walkers(known) == {PACKING}, sorted(field_walkers(known))
    assert rebuild_writers(known) == {PACKING}, sorted(rebuild_writers(known))
    for caller in PACKING_CALLERS:
        assert PACKING in graph[caller], f"{caller} does not import {PACKING}"


def test_the_packing_walks_see_the_forms_they_look_for(tmp_path):
    (tmp_path / "a.py").write_text(
        "def pack(params):\n    return [float(x) for t in params for x in t]\n")
    (tmp_path / "b.py").write_text(
        "def pack(args):\n    out = []\n    for p in args:\n        for x in p:\n"
        "            out.append(x)\n    return out\n")
    (tmp_path / "c.py").write_text("def src(k):\n    return f'ip[{k}] != 0'\n")
    (tmp_path / "d.py").write_text("X = 'row[o + 3] != 0.0'\n"
                                   "rows = [[0.0] * 3 for _ in range(2)]\n"
                                   "for r in rows:\n    for j in range(3):\n        pass\n")
    known = {f"rodjit.{n}": tmp_path / f"{n}.py" for n in "abcd"}
    assert field_walkers(known) == {"rodjit.a", "rodjit.b"}
    assert rebuild_writers(known) == {"rodjit.c", "rodjit.d"}


# ---- one implementation of a point's set-up ----------------------------------------------
SETUP = "rodjit.driver.setup"
# what a point's set-up makes of its Config: the run checks' sections aside, the functions
# of the floors below that make its pieces
SETUP_NAMES = ("rod_system", "law_params", "build_system", "flight_time", "make_scheme",
               "initial_state", "check_admissible", "clock_row")
# the modules that set points up: a single run, the CPU engine's batches, the GPU engine
SETUP_CALLERS = ("rodjit.driver.run", "rodjit.sweeps.ensemble", "rodjit.gpu.engine")


def _uses(tree, name: str) -> bool:
    """Whether ``tree`` reads ``name`` (a call, or the function handed on), as a name or
    as an attribute of a module (``control.build`` for ``name == "control.build"``)."""
    owner, _, attr = name.rpartition(".")
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and not owner and node.id == attr \
                and isinstance(node.ctx, ast.Load):
            return True
        if isinstance(node, ast.Attribute) and node.attr == attr and (
                not owner or (isinstance(node.value, ast.Name) and node.value.id == owner)):
            return True
    return False


def test_a_points_set_up_has_one_implementation(graph):
    """One module sets a point up from its Config (``driver.setup``: the parameter tuples,
    the initial state checked admissible, the clock row, the flight time): a single run,
    the CPU engine's batches and the GPU engine take it from there, and no module of the
    driver's floor or above makes a piece of it itself.  (Below the driver, the run file
    and the first-impact stream read the flight time for themselves: they are no set-up.)"""
    known = modules()
    for caller in SETUP_CALLERS:
        assert SETUP in graph[caller], f"{caller} does not import {SETUP}"
    trees = {name: ast.parse(path.read_text(), str(path)) for name, path in known.items()
             if floor(name) >= FLOOR_OF["driver"]}
    for name in (*SETUP_NAMES, "control.build"):
        users = {mod for mod, tree in trees.items() if _uses(tree, name)}
        assert users <= {SETUP}, (name, sorted(users))
        # the set-up makes the system and the laws' parameters apart (``build_system``
        # makes both at once, for benchmarks and tests)
        assert name == "build_system" or SETUP in users, name


def test_the_set_up_walk_sees_names_handed_on_and_module_attributes():
    tree = ast.parse("from x import flight_time\nimport control\n"
                     "def f(c):\n    return get(flight_time, c), control.build(c)\n")
    assert _uses(tree, "flight_time") and _uses(tree, "control.build")
    assert not _uses(tree, "initial_state")
    assert not _uses(ast.parse("aot.build(1)\n"), "control.build")


# ---- one per-point driver and one reading of its results ---------------------------------
DRIVER = "rodjit.stepping.trajectory"
DECODER = "rodjit.sweeps.decode"
# the modules that take the loop's ``advance`` kernel: the per-point driver (either sweep
# engine), a single run's driver (``Run``) and the ahead-of-time extension (its entry)
ADVANCE_TAKERS = {DRIVER, "rodjit.driver.run", "rodjit.stepping.aot"}
# result columns the CPU batch kernel reads to place a point's bounce rows and go on
BATCH_BOOKKEEPING = {"I_STOPPED", "I_BOUNCES", "I_BSTART"}


def _names_read(tree) -> set[str]:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            out.add(node.id)
        elif isinstance(node, ast.Attribute):
            out.add(node.attr)
        elif isinstance(node, ast.alias):
            out.add(node.name)
    return out


def test_a_sweep_points_run_has_one_driver_and_one_decoder(graph):
    """One compiled function runs a sweep point (``stepping.trajectory.run_one``: the CPU
    engine's batch kernel loops over it, a GPU thread calls it) and one module reads its
    results into summary columns and bounce tables (``sweeps.decode``), for both engines:
    no other module takes the loop's ``advance`` besides a single run's driver, none
    other reads the driver's result columns (the batch kernel only its rows' bookkeeping),
    and both engines' hosts decode through the decoder."""
    known = modules()
    trees = {name: ast.parse(path.read_text(), str(path)) for name, path in known.items()}
    takers = set()
    for name, tree in trees.items():
        for node in ast.walk(tree):
            if (isinstance(node, ast.ImportFrom) and node.module
                    and node.module.endswith("loop")
                    and any(a.name == "advance" for a in node.names)):
                takers.add(name)
    assert takers == ADVANCE_TAKERS, sorted(takers)
    _, constants = definitions(known)
    results = {c for c, mods in constants.items() if DRIVER in mods
               and re.fullmatch(r"[FI]_\w+|BAD_DIAGNOSTICS", c) and not c.endswith("_SIZE")}
    assert {"F_ENERGY_ERROR", "F_IMPACT", "I_CODE", "I_STOPPED"} <= results
    readers = {name: _names_read(tree) & results for name, tree in trees.items()
               if DRIVER in graph[name] and _names_read(tree) & results}
    assert set(readers) == {"rodjit.stepping.ensemble", DECODER}, sorted(readers)
    assert readers["rodjit.stepping.ensemble"] <= BATCH_BOOKKEEPING
    for host in ("rodjit.sweeps.ensemble", "rodjit.gpu.engine"):
        assert DECODER in graph[host], host
        assert _calls_of(trees[host], "summarize") and _calls_of(trees[host], "bounce_tables")
    callers = {name for name, tree in trees.items() if _calls_of(tree, "run_one")}
    assert callers == {"rodjit.stepping.ensemble", "rodjit.gpu.kernel"}, sorted(callers)
