"""The scheme registry, the kick–drift–kick stage table and the step-control rules."""
import ast
import dataclasses
import importlib
import math
from pathlib import Path

import numba
import numpy as np
import pytest

import rodjit
from rodjit import config
from rodjit.kernels.forces import OK
from rodjit.kernels.mass import inv_node_mass, node_mass
from rodjit.model.system import masses
from rodjit.stepping import control, registry, schemes, workspace
from rodjit.stepping.integrators import kdk
from rodjit.stepping.step_result import StepResult

ROOT = Path(rodjit.__file__).resolve().parent


def test_config_takes_the_integrator_names_from_the_registry():
    assert config.INTEGRATORS == registry.NAMES == tuple(s.name for s in registry.SCHEMES)
    assert len(set(registry.NAMES)) == len(registry.NAMES)
    for name in registry.NAMES:
        assert rodjit.Config().override({"time.integrator": name}).time.integrator == name
    with pytest.raises(ValueError, match="time.integrator"):
        rodjit.Config().override({"time.integrator": "rk4"})


def test_every_entry_names_a_module_with_its_parameters_and_kernels():
    tc = rodjit.Config().time
    for entry in registry.SCHEMES:
        module, params = registry.load(entry)
        assert module is importlib.import_module(entry.module)
        assert callable(module.initial) and callable(module.step)
        scheme = registry.make_scheme(dataclasses.replace(tc, integrator=entry.name))
        assert type(scheme) is params
        assert registry.entry_of(params) is entry
        assert schemes.gap_control(scheme) is entry.gap_control
        assert schemes.work_rows(scheme) == entry.work_rows
        assert set(entry.counters) <= set(registry.SCHEME_STATS)


def test_work_rows_and_counters_match_the_scheme_modules():
    from rodjit.stepping.integrators import energy
    assert registry.get("energy").work_rows == energy.WORK_ROWS
    assert registry.get("verlet").work_rows == workspace.WORK_ROWS
    # the sstats layout of run files and Result.stats
    assert registry.SCHEME_STATS == ("newton_iterations", "newton_failures")
    assert (energy.NEWTON_ITERATIONS, energy.NEWTON_FAILURES) == (0, 1)
    assert registry.get("energy").gap_control is False
    assert registry.get("verlet").gap_control and registry.get("semi-implicit").gap_control


def test_the_registry_imports_no_compiled_code():
    """config imports the registry to validate names: it must not pull in the schemes."""
    for mod in ("stepping/registry.py", "stepping/workspace.py"):
        tree = ast.parse((ROOT / mod).read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                assert node.level == 0 or node.module in (None, "workspace"), (mod, node.module)
                if node.level == 0:
                    assert node.module in ("__future__", "dataclasses", "typing"), node.module
            elif isinstance(node, ast.Import):
                assert all(a.name in ("importlib",) for a in node.names), mod


def test_an_unknown_integrator_is_refused_by_name():
    with pytest.raises(ValueError, match="time.integrator = 'nope'.*energy"):
        registry.get("nope")
    with pytest.raises(TypeError, match="registered integrator"):
        registry.entry_of(tuple)


def test_load_gives_each_schemes_module_and_parameter_class_once_imported():
    for entry in registry.SCHEMES:
        first = registry.load(entry)
        module = importlib.import_module(entry.module)
        assert first == (module, getattr(module, entry.params))
        assert registry.load(entry) is first          # kept, not looked up again
        assert registry.entry_of(first[1]) is entry


def test_adding_a_scheme_is_one_module_and_one_registry_line(monkeypatch):
    line = registry.Scheme("toy", "toy_scheme", "Toy", lambda tc, P: P(float(tc.cfl)),
                           workspace.WORK_ROWS, counters=("newton_iterations",))
    monkeypatch.setattr(registry, "SCHEMES", registry.SCHEMES + (line,))
    tc = type("TC", (), {"integrator": "toy", "cfl": 0.25})()
    scheme = registry.make_scheme(tc)
    assert type(scheme).__name__ == "Toy" and scheme.cfl == 0.25
    assert schemes.gap_control(scheme) and schemes.work_rows(scheme) == workspace.WORK_ROWS

    # the loop's dispatch finds the new module from the parameters' (Numba) type
    import toy_scheme
    assert schemes._module_for(numba.typeof(scheme)) is toy_scheme
    # (called from Python here: the compiled dispatch's cache must not name a module that
    # only the tests can import)
    from rodjit.model.system import build_system, initial_state
    cfg = rodjit.Config().override({"rod.N": 8})
    system, rod, floor = build_system(cfg)
    u, v = initial_state(cfg)
    state = np.zeros((3, 9))
    state[0], state[1] = u, v
    trial = np.zeros((3, 9))
    work = np.zeros((schemes.work_rows(scheme), 9))
    sstats = np.zeros(len(registry.SCHEME_STATS), dtype=np.int64)
    r0 = schemes.initial(scheme, system, rod, floor, state[0], state[1], state[2], work)
    r = schemes.step(scheme, system, rod, floor, state[0], state[1], state[2],
                     trial[0], trial[1], trial[2], work, sstats, 1e-4)
    assert isinstance(r, StepResult) and (r0.status, r.status) == (OK, OK)
    assert sstats[registry.counter_index("newton_iterations")] == 1
    # symplectic Euler: one step moves every node by dt·(v + dt·a)
    np.testing.assert_allclose(trial[0], u + 1e-4 * (v + 1e-4 * state[2]), rtol=0, atol=1e-15)
    np.testing.assert_allclose(r.w, (masses(8) * trial[1]).sum(), rtol=1e-14)



def test_the_loop_compiles_each_scheme_kernel_itself_not_a_wrapper(monkeypatch):
    """rodjit's schemes compile ``initial`` with the kernel options and ``step`` with the
    step options, so the loop's dispatch compiles their own source (no wrapper optimised
    again with the whole step inlined into it, benchmarks/cold_start.py); a scheme kernel
    compiled otherwise (the toy scheme's plain-kernel step) is called through a wrapper."""
    from rodjit._jit import JIT_OPTIONS, load_numba
    load_numba()
    for entry in registry.SCHEMES:
        module, _ = registry.load(entry)
        scheme = registry.make_scheme(rodjit.Config().override(
            {"time.integrator": entry.name}).time)
        nt = numba.typeof(scheme)
        assert schemes._initial_ov(nt, *[None] * 7) is module.initial.py_func, entry.name
        assert schemes._step_ov(nt, *[None] * 12) is module.step.py_func, entry.name
        assert not schemes._compiled_with(module.step, JIT_OPTIONS)
    line = registry.Scheme("toy", "toy_scheme", "Toy", lambda tc, P: P(float(tc.cfl)),
                           workspace.WORK_ROWS)
    monkeypatch.setattr(registry, "SCHEMES", registry.SCHEMES + (line,))
    import toy_scheme
    assert schemes._compiled_with(toy_scheme.step, JIT_OPTIONS)
    wrapper = schemes._step_ov(numba.typeof(toy_scheme.Toy(0.5)), *[None] * 12)
    assert wrapper is not toy_scheme.step.py_func and wrapper.__name__ == "<lambda>"


# ---- the kick–drift–kick stage table --------------------------------------------------------
def test_every_kdk_scheme_has_a_row_of_the_stage_table():
    kdk_entries = [e for e in registry.SCHEMES if e.module == kdk.__name__]
    assert {e.name for e in kdk_entries} == {"verlet", "semi-implicit"}
    assert {getattr(kdk, e.params) for e in kdk_entries} == set(kdk.STAGES)
    v = kdk.STAGES[kdk.Verlet]
    s = kdk.STAGES[kdk.SemiImplicit]
    assert (v.kick_bending, v.drift, v.viscous, v.viscous_limit) == (
        True, kdk.DRIFT, kdk.CRANK_NICOLSON, True)
    assert (s.kick_bending, s.drift, s.viscous, s.viscous_limit) == (
        False, kdk.BEAM_MIDPOINT, kdk.IMEX_KICK, False)
    assert kdk.stages(kdk.Verlet(0.1)) is v

    @numba.njit
    def row(scheme):
        st = kdk.stages(scheme)
        return st.kick_bending, st.drift, st.viscous, st.viscous_limit

    assert row(kdk.Verlet(0.1)) == tuple(v)
    assert row(kdk.SemiImplicit(0.1)) == tuple(s)


def test_the_two_rows_coincide_where_their_differing_stages_are_inactive():
    """γ = μ = 0: bending, the beam drift and the viscous sub-steps all vanish, so both
    rows of the table are the same scheme, bit for bit."""
    base = {"rod.N": 10, "rod.gamma": 0.0, "rod.mu": 0.0, "time.t_end": 0.4,
            "initial.height": 0.05, "initial.velocity": -1.0}
    a = rodjit.simulate(rodjit.Config().override({**base, "time.integrator": "verlet"}))
    b = rodjit.simulate(rodjit.Config().override({**base, "time.integrator": "semi-implicit"}))
    assert a.stats["steps"] == b.stats["steps"] and len(a.bounces["t_impact"]) >= 1
    np.testing.assert_array_equal(a.u, b.u)
    for name in a.diagnostics:
        np.testing.assert_array_equal(a.diagnostics[name], b.diagnostics[name])
    # with bending on, the rows differ
    g = {**base, "rod.gamma": 1e-3}
    c = rodjit.simulate(rodjit.Config().override({**g, "time.integrator": "verlet"}))
    d = rodjit.simulate(rodjit.Config().override({**g, "time.integrator": "semi-implicit"}))
    assert not np.array_equal(c.u, d.u)


def test_step_result_is_named():
    assert StepResult._fields == ("status", "value", "min_strain", "floor_force",
                                  "dt_suggest", "w", "dissipated")


# ---- step control --------------------------------------------------------------------------
def test_control_from_the_time_config():
    tc = rodjit.Config().override({"time.cfl": 0.9, "time.dt_max": 0.01}).time
    c = control.build(tc, kdk.Verlet(0.9))
    rules = control.RULES["second-order"]
    assert c == control.Control(dt_max=0.01, dt_min=tc.dt_min, dt_fixed=0.0,
                                growth=control.GROWTH, growth_reject=rules.growth_reject,
                                land=rules.land, split=rules.split, gap=control.GAP_MAX)
    c = control.build(rodjit.Config().time, kdk.SemiImplicit(0.05))
    assert c.gap == 0.05 and c.dt_max == math.inf
    from rodjit.stepping.integrators.energy import Energy
    c = control.build(rodjit.Config().override({"time.dt": 1e-4}).time, Energy(1e-6, 1e-9))
    assert c.gap == 0.0 and c.dt_fixed == 1e-4
    assert control.output_tolerance([0.5, 0.001, 2.0]) == control.OUTPUT_TOL * 0.001


def test_steps_land_on_output_times_and_never_leave_a_sliver():
    dtp = 0.1
    c = control.build(rodjit.Config().time, kdk.Verlet(0.5))     # the second-order rules
    assert control.step_to(c, False, 0.1 * (1 + 1e-7), dtp) == (0.1 * (1 + 1e-7), True)
    assert control.step_to(c, False, 0.15, dtp) == (0.075, False)     # two equal steps
    assert control.step_to(c, False, 0.25, dtp) == (dtp, False)
    assert control.step_to(c, True, 0.15, dtp) == (dtp, False)        # fixed: never halved
    assert control.step_to(c, True, 0.1 * (1 + 1e-10), dtp) == (0.1 * (1 + 1e-10), True)
    assert control.step_to(c, True, 0.1 * (1 + 1e-7), dtp) == (dtp, False)


def test_growth_rejection_and_gap_rules():
    c = control.Control(dt_max=1.0, dt_min=1e-12, dt_fixed=0.0, growth=1.5,
                        growth_reject=1.0, land=control.LAND_ADAPTIVE,
                        split=control.SPLIT_BELOW, gap=0.05)
    assert control.propose(c, 10.0, 0.1) == pytest.approx(0.15)
    assert control.propose(c, 10.0, 0.1, True) == pytest.approx(0.1)   # after a rejection
    assert control.propose(c, 0.01, 0.1) == 0.01
    assert control.propose(c._replace(dt_fixed=0.3), 0.01, 0.1) == 0.3
    assert control.retry(True, 0.02, 0.1) == 0.02
    assert control.retry(False, 0.02, 0.1) == control.REJECT_SHRINK * 0.1
    assert control.gap_limit(c, 0.1, 1.0, 2.0) == np.inf           # the gap opens
    # closing 0.5 per 0.1 s with 0.5 left: 5 % of it takes 0.005 s
    assert control.gap_limit(c, 0.1, 1.0, 0.5) == pytest.approx(0.005)
    assert control.gap_keep(c) == pytest.approx(0.9)
    assert control.gap_keep(c._replace(gap=0.5)) == pytest.approx(1 - control.GAP_CLOSE_MAX)


def test_node_mass_kernel_matches_the_mass_vector():
    for n in (1, 2, 5, 17):
        h = 1.0 / n
        m = np.array([node_mass(i, n, h) for i in range(n + 1)])
        np.testing.assert_array_equal(m, masses(n))
        im = np.array([inv_node_mass(i, n, 1.0 / h) for i in range(n + 1)])
        np.testing.assert_array_equal(im, 1.0 / m)


# ---- the registry's facts and registration from outside --------------------------------
def test_every_scheme_states_its_order_step_keys_cap_and_norm():
    for entry in registry.SCHEMES:
        assert entry.order >= 2 and entry.error_norm, entry.name
        assert entry.step_keys("tolerance") == ("time.rtol", "time.atol")
        assert entry.step_keys("cfl", fixed=True) == ("time.dt",)
        assert set(entry.cap_keys) <= set(registry.TIME_KEYS)
        assert entry.step_keys("cfl") == (("time.cfl",) if entry.cfl_control else
                                          ("time.rtol", "time.atol"))
    assert {e.name for e in registry.SCHEMES if e.cfl_control} == {"verlet", "semi-implicit"}
    assert {e.name: e.order for e in registry.SCHEMES} == {
        "verlet": 2, "semi-implicit": 2, "energy": 2, "dp54": 5, "dop853": 8, "radau5": 5}
    assert registry.get("verlet").viscous_mu_max == config.VERLET_MU_MAX == 1.0
    assert all(e.viscous_mu_max == float("inf") for e in registry.SCHEMES if e.name != "verlet")


def _toy_line(**kw):
    return registry.Scheme("toy", "toy_scheme", "Toy", lambda tc, P: P(float(tc.cfl)),
                           workspace.WORK_ROWS, counters=("newton_iterations",),
                           cfl_control=True, order=1, **kw)


def test_a_scheme_registers_from_outside_as_a_law_does(monkeypatch):
    monkeypatch.setattr(registry, "SCHEMES", registry.SCHEMES)
    monkeypatch.setattr(registry, "NAMES", registry.NAMES)
    with pytest.raises(ValueError, match="time.integrator"):
        rodjit.Config().override({"time.integrator": "toy"})
    line = registry.register(_toy_line())
    assert registry.get("toy") is line and "toy" in registry.NAMES
    cfg = rodjit.Config().override({"time.integrator": "toy", "time.control": "cfl"})
    assert registry.make_scheme(cfg.time).cfl == cfg.time.cfl
    # named through the registered namespace, so a cache index naming it never fails to load
    _, params = registry.load(line)
    assert params.__module__ == "rodjit.stepping.registered"
    from rodjit.analysis.converge import default_time_ladder
    assert list(default_time_ladder(cfg)) == ["time.cfl"]
    with pytest.raises(ValueError, match="already registered"):
        registry.register(_toy_line())
    with pytest.raises(ValueError, match="not among"):
        registry.register(dataclasses.replace(_toy_line(), name="toy2",
                                              counters=("toy_counter",)))
    with pytest.raises(TypeError, match="registry.Scheme"):
        registry.register("toy")


@pytest.mark.slow   # compiles the whole loop for the toy's parameter type
def test_a_registered_scheme_runs_and_leaves_the_cache_usable(tmp_path):
    import subprocess
    import sys
    here = Path(__file__).parent
    run = ("import rodjit; r = rodjit.simulate(rodjit.Config().override({'rod.N': 8, "
           "'time.t_end': 0.05, 'time.integrator': %r, 'time.control': 'cfl', "
           "'time.cfl': 0.2})); print(r.status, r.stats['steps'], r.stats['newton_iterations'])")
    reg = ("from rodjit.stepping import registry, workspace; registry.register("
           "registry.Scheme('toy', 'toy_scheme', 'Toy', lambda tc, P: P(float(tc.cfl)), "
           "workspace.WORK_ROWS, counters=('newton_iterations',), cfl_control=True)); ")
    out = subprocess.run([sys.executable, "-c", reg + run % "toy"], cwd=here,
                         capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stderr
    status, steps, counted = out.stdout.split()
    assert status == "completed" and int(steps) == int(counted) > 0
    # a process that cannot import the toy's module still loads the cache
    out = subprocess.run([sys.executable, "-c", run % "verlet"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stderr
