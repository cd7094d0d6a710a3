"""Dense output of dp54, dop853 and radau5 (``output.interpolate``, on by default).

Checked: the continuous extensions' order (4 for dp54, 7 for dop853, the stage order 3 for
radau5: local error of the interpolant ∝ h^(p+1)), the pairs' caps that keep the
interpolated rows from growing any mode, their ends (θ = 0 the old state, θ = 1 the new one, the dissipated
energy likewise), that the steps no longer depend on the output schedule, the accuracy of
a bouncing run's rows against a tight reference (the same order as landing, in fewer
steps), runs cut into calls, buffers and files bit for bit, ``output.interpolate = false``
landing as before, and the key's validation.
"""
import warnings

import numpy as np
import pytest

import rodjit
from conftest import assert_resume_is_bit_identical, assert_same_files
from rodjit import presets
from rodjit.config import Config, ModelWarning
from rodjit.driver.run import Run
from rodjit.model import reference
from rodjit.model.system import build_system
from rodjit.records.result import MemorySink
from rodjit.stepping import control, layout as L, registry
from rodjit.stepping.integrators import erk
from rodjit.stepping.integrators.kdk import Verlet

PAIRS = {"dp54": 4, "dop853": 7}       # the order of each pair's continuous extension
# every integrator with a dense output, and its order: radau5's collocation polynomial has
# the stage order 3
DENSE = {**PAIRS, "radau5": 3}
QUIET = {"output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0}
# a smooth flight far above the floor: pre-strained, vibrating, viscous (μ > 0 puts v into
# the acceleration; at μ = 0, u'' = g(u), dop853's extension converges an order faster)
FLIGHT = {"rod.N": 5, "rod.kappa": 1.0, "rod.mu": 0.3, "initial.height": 3.0,
          "initial.strain": 0.3, "initial.velocity": 0.0, **QUIET}
# step sizes h, h/2, h/4 in the asymptotic range, errors above rounding (≥ 1e-13)
STEPS = {"dp54": 1e-2, "dop853": 4e-2, "radau5": 2e-2}
THETAS = (0.25, 0.5, 0.75)


def _cfg(integrator, **over):
    return Config().override({"time.integrator": integrator, **over})


def _paper(integrator, **over):
    """The paper's μ = 0 run over 1 s, outputs every 5 ms."""
    return presets.load_preset("paper-mu0").override({
        "time.integrator": integrator, "time.t_end": 1.0, "output.snapshot_interval": 0.005,
        "output.diagnostics_interval": 0.005, **over})


def _simulate(cfg):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)    # μ = γ = 0: shocks
        return rodjit.simulate(cfg)


def _one_step(integrator, h, thetas, **over):
    """One step of length h from the initial state, then the dense output at each θ:
    (old (u, v), new (u, v), [interpolated (u, v)], [dissipated to θ], step's dissipated)."""
    run = Run(_cfg(integrator, **{**FLIGHT, **over}))
    run.start(MemorySink())
    scheme, _, system, rod, floor, _ = run._args()
    s = run.arrays.state
    new = np.zeros_like(s)
    mod = registry.load(registry.get(integrator))[0]
    r = mod.step(scheme, system, rod, floor, s[0], s[1], s[2], new[0], new[1], new[2],
                 run.arrays.work, run.arrays.sstats, h)
    assert r.status in (erk.OK, erk.INACCURATE)    # a valid state (its error aside)
    status, _ = mod.dense_setup(scheme, system, rod, floor, s[0], s[1], s[2], new[0], new[1],
                                new[2], run.arrays.work, h)
    assert status == erk.OK
    out, diss = [], []
    for theta in thetas:
        y = np.zeros((2, s.shape[1]))
        mod.dense(scheme, s[0], s[1], s[2], new[0], new[1], new[2], run.arrays.work, h, theta,
                  y[0], y[1])
        out.append(y)
        diss.append(mod.dense_dissipated(scheme, system, floor, s[0], s[1], new[0], new[1],
                                         run.arrays.work, h, theta))
    return s[:2].copy(), new[:2], out, diss, r.dissipated


def _exact(t):
    """The flight at time t: dop853 in 64 fixed steps ending exactly there."""
    res = rodjit.simulate(_cfg("dop853", **FLIGHT, **{"time.t_end": t, "time.dt": t / 64}))
    return np.array([res.u_final, res.v_final])


# ---- the continuous extensions ----------------------------------------------------------
def _stage_matrix(params):
    """The coefficients of every stage index (the pair's stages, the new point, the extra
    stages) over the earlier ones, as one strictly lower triangular matrix."""
    t, d = erk.TABLEAUS[params], erk.DENSE[params]
    ns, se = t.b.size, d.d.shape[1]
    a = np.zeros((se, se))
    a[:ns, :ns - 1] = t.a
    a[ns, :ns] = t.b
    a[ns + 1:, :] = d.ax
    return a


def _weights(params, theta):
    """The extension as y(θ) = yⁿ + dt Σ_j b_j(θ) k_j over the stage indices, and the
    stages' nodes c_j."""
    t, d = erk.TABLEAUS[params], erk.DENSE[params]
    ns, se = t.b.size, d.d.shape[1]
    a = _stage_matrix(params)
    delta = np.zeros(se)
    delta[:ns] = t.b
    b = np.eye(se)[0] - delta
    c = delta - np.eye(se)[ns] - b
    tail = np.zeros(se)
    for k in range(d.d.shape[0] - 1, -1, -1):
        tail = (1 - theta if k % 2 == 0 else theta) * (d.d[k] + tail)
    return theta * (delta + (1 - theta) * (b + theta * (c + tail))), a.sum(axis=1)


@pytest.mark.parametrize("params", [erk.DP54, erk.DOP853])
def test_the_published_coefficients_meet_the_quadrature_conditions(params):
    """Σ_j b_j(θ) c_j^(k−1) = θ^k / k for k up to the extension's order, at every θ (the
    extra stages' nodes are 0.1, 0.2, 7/9): a wrong digit in a coefficient shows here."""
    assert set(erk.DENSE) == {erk.DP54, erk.DOP853}
    order = PAIRS["dp54" if params is erk.DP54 else "dop853"]
    for theta in (0.2, 0.5, 0.9, 1.0):
        w, c = _weights(params, theta)
        for k in range(1, order + 1):
            assert abs(w @ c ** (k - 1) - theta ** k / k) < 1e-13, (theta, k)
    if params is erk.DOP853:
        np.testing.assert_allclose(c[-3:], [0.1, 0.2, 7 / 9], rtol=0, atol=1e-15)


def _amplification(params, z, theta):
    """|y(θ)| for y' = λy, y⁰ = 1, z = λ dt, from the extension's weights b_j(θ) over the
    stages of the linear problem solved as a dense system (independent of the
    vectorised recursion of ``erk.dense_amplification``)."""
    a = _stage_matrix(params)
    se = a.shape[0]
    k = z * np.linalg.solve(np.eye(se) - z * a, np.ones(se))    # dt·f of every stage
    w, _ = _weights(params, theta)
    return abs(1.0 + w @ k)


@pytest.mark.parametrize("params", [erk.DP54, erk.DOP853])
def test_the_caps_keep_every_mode_from_growing_in_the_rows(params):
    """Inside the caps no mode grows between a step's ends by more than DENSE_GROWTH: on
    the half disc |z| ≤ STABILITY_CAP (every underdamped mode, |z| = ω_k dt) and on the
    real axis down to −VISCOUS_CAP (overdamped ones); just beyond the limits a mode does
    grow (dop853: by about 15 near ±5.9i and −6, which gave rows with 10⁴ × E0)."""
    r, x = erk.STABILITY_CAP[params], erk.VISCOUS_CAP[params]
    worst = max(_amplification(params, rho * np.exp(1j * phi), th)
                for rho in np.linspace(0.05, 1.0, 12) * r
                for phi in np.linspace(np.pi / 2, np.pi, 13)
                for th in np.linspace(0.0, 1.0, 21))
    assert worst <= erk.DENSE_GROWTH, worst
    worst_real = max(_amplification(params, -xx, th) for xx in np.linspace(0.05, 1.0, 40) * x
                     for th in np.linspace(0.0, 1.0, 41))
    assert worst_real <= erk.DENSE_GROWTH, worst_real
    y_lim, x_lim = erk.dense_limits(params)
    if y_lim < np.inf:
        assert max(_amplification(params, 1.05j * y_lim, th)
                   for th in np.linspace(0, 1, 101)) > erk.DENSE_GROWTH
    assert max(_amplification(params, -1.05 * x_lim, th)
               for th in np.linspace(0, 1, 101)) > erk.DENSE_GROWTH
    # the vectorised scan agrees with this construction
    z = np.array([0.7j * r, -0.5 * x, r * np.exp(2.5j)])
    np.testing.assert_allclose(
        erk.dense_amplification(params, z, [0.3, 0.8]),
        [[_amplification(params, zz, th) for th in (0.3, 0.8)] for zz in z], rtol=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("integrator", sorted(DENSE))
def test_interpolation_error_scales_as_h_to_the_order_plus_one(integrator):
    hs = STEPS[integrator] / 2.0 ** np.arange(3)
    errs = []
    for h in hs:
        _, _, ys, _, _ = _one_step(integrator, h, THETAS)
        errs.append(max(np.abs(y - _exact(th * h)).max() for th, y in zip(THETAS, ys)))
    errs = np.array(errs)
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert errs[-1] > 1e-13, errs                        # above rounding
    assert abs(slope - (DENSE[integrator] + 1)) <= 0.3, (slope, errs)


@pytest.mark.parametrize("integrator", sorted(DENSE))
def test_the_ends_are_the_old_and_the_new_state(integrator):
    h = STEPS[integrator]
    old, new, ys, diss, step_diss = _one_step(integrator, h, (0.0, 1e-9, 1.0))
    np.testing.assert_array_equal(ys[0], old)           # θ = 0: exactly
    scale = np.abs(new).max()
    np.testing.assert_allclose(ys[2], new, rtol=0, atol=4 * np.finfo(float).eps * scale)
    assert np.abs(ys[1] - old).max() <= 1e-8 * np.abs(new - old).max()     # θ → 0
    # the dissipated energy: 0 at the start, the step's own increment at its end
    assert diss[0] == 0.0 and step_diss > 0.0
    assert abs(diss[2] - step_diss) < 1e-14 * step_diss
    assert 0.0 < diss[1] < 1e-6 * step_diss


# ---- the loop ---------------------------------------------------------------------------
@pytest.mark.parametrize("integrator", sorted(DENSE))
def test_steps_do_not_depend_on_the_output_schedule(integrator):
    """Interpolated outputs cost no steps: the run with snapshots and diagnostics every
    5 ms takes exactly the steps of the run without outputs (both land on t_end), and its
    rows are at the exact grid times, the last one the final state itself."""
    cfg = _paper(integrator, **{"time.t_end": 0.6, "time.rtol": 1e-6, "time.atol": 1e-6})
    res, quiet = _simulate(cfg), _simulate(cfg.override(QUIET))
    assert res.stats["steps"] == quiet.stats["steps"]
    assert res.stats["rejected_steps"] == quiet.stats["rejected_steps"]
    np.testing.assert_array_equal(res.u_final, quiet.u_final)
    np.testing.assert_array_equal(res.t, np.arange(121) * 0.005)
    np.testing.assert_array_equal(res.diagnostics["t"], res.t)
    np.testing.assert_array_equal(res.u[-1], res.u_final)
    assert res.n_bounces >= 1
    # each diagnostics row is the energy of its snapshot's (interpolated) state
    system, rod, floor = build_system(cfg)
    for k in range(0, 121, 7):
        e = reference.energies(res.u[k], res.v[k], system, rod, floor)["energy_total"]
        assert abs(res.diagnostics["energy_total"][k] - e) < 1e-12 * abs(e)


def _reference_rows(cfg):
    return _simulate(cfg.override({"time.integrator": "dop853", "time.rtol": 1e-13,
                                   "time.atol": 1e-15, "output.interpolate": False}))


@pytest.mark.parametrize("integrator", sorted(PAIRS))
def test_a_bouncing_run_is_as_accurate_in_fewer_steps(integrator):
    """paper-mu0 over 1 s (the fall, the first bounce, chatter) at rtol = atol = 1e-6: the
    interpolated rows are within a small factor of the landed ones' distance to a tight
    reference (the landed run's steps are shortened by the 5 ms outputs, so it is more
    accurate than its tolerance asks), and the run takes fewer steps.  In the free fall
    before the first impact, whose internal modes are not excited, the step is capped by
    the pair's stability on the imaginary axis (``erk.STABILITY_CAP``), so the rows stay
    at rounding level although the error estimate alone would let the steps grow far
    beyond it."""
    cfg = _paper(integrator, **{"time.rtol": 1e-6, "time.atol": 1e-6})
    ref = _reference_rows(cfg)
    dense, land = _simulate(cfg), _simulate(cfg.override({"output.interpolate": False}))
    err = {}
    for name, res in (("dense", dense), ("land", land)):
        np.testing.assert_array_equal(res.t, ref.t)
        err[name] = (np.abs(res.u - ref.u).max(), np.abs(res.v - ref.v).max())
    assert err["dense"][0] < 4 * err["land"][0] and err["dense"][0] < 1e-5, err
    assert err["dense"][1] < 8 * err["land"][1], err
    cost = {n: r.stats["steps"] + r.stats["rejected_steps"] for n, r in (("dense", dense),
                                                                        ("land", land))}
    assert dense.stats["steps"] < land.stats["steps"] and cost["dense"] < cost["land"], cost
    fall = dense.t < ref.bounces["t_impact"][0] - 0.01
    assert fall.sum() > 50
    assert np.abs(dense.u[fall] - ref.u[fall]).max() < 1e-12


@pytest.mark.parametrize("integrator", ["dp54", "dop853", "radau5"])
def test_rows_at_a_loose_tolerance_keep_the_energy(integrator):
    """paper-mu0 at rtol = atol = 1e-2 (long steps through the contacts): no row's energy
    leaves E0 by more than 5 %.  An extension whose stability function exceeds 1 inside the
    step amplifies the stiff components of a contact between the step's ends (dop853's
    reaches about 15 beyond its caps: uncapped, rows had 10⁴ × E0)."""
    res = _simulate(_paper(integrator, **{"time.rtol": 1e-2, "time.atol": 1e-2}))
    e = res.diagnostics["energy_total"]
    assert e.size == 201
    assert np.abs(e - res.energy0).max() < 0.05 * res.energy0, np.abs(e - res.energy0).max()
    assert np.abs(res.u).max() <= 2.0 + 1e-9          # no row above the rod's drop height


def test_free_flight_steps_stay_inside_the_stability_region():
    """A rod falling from far above the floor: no output and no contact limits the steps,
    so only the cap does; every step keeps ω·dt ≤ STABILITY_CAP (ω the Gershgorin bound,
    the diagnostics' ``dt`` column being the proposal) and the motion stays the exact
    parabola to rounding."""
    from rodjit.stepping.integrators.erk import STABILITY_CAP, DP54, DOP853
    for integrator, params in (("dp54", DP54), ("dop853", DOP853)):
        cfg = _paper(integrator, **{"initial.height": 50.0, "time.t_end": 2.0,
                                    "output.snapshot_interval": 0.5,
                                    "output.diagnostics_interval": 0.5})
        res = _simulate(cfg)
        t = res.t
        exact = (cfg.initial.height + cfg.initial.velocity * t
                 - 0.5 * abs(cfg.gravity.g) * t ** 2)
        drift = np.abs(res.u - res.u[:, :1] - (res.u[0] - res.u[0, 0])).max()
        assert np.abs(res.u[:, 0] - exact).max() < 1e-9 * cfg.initial.height, integrator
        assert drift < 1e-10, integrator   # uncapped: 5e-6 (dp54), 6e-7 (dop853)
        cap = STABILITY_CAP[params] / _omega_bound(cfg)
        proposals = res.diagnostics["dt"]
        assert proposals.max() <= cap * (1.0 + 1e-9), integrator
        assert proposals[1:].min() > 0.5 * cap, integrator   # and the cap is what binds


def _omega_bound(cfg):
    """The Gershgorin bound of the rod's highest frequency at its rest length (as the
    compiled ``accel`` computes it): the free fall keeps that shape exactly."""
    from rodjit.kernels.forces import accel
    from rodjit.model.system import build_system, initial_state
    system, rod, floor = build_system(cfg)
    u, v = initial_state(cfg)
    n1 = u.size
    out = accel(u, np.zeros(n1), np.zeros(n1), np.zeros(n1), system, rod, floor, True, True)
    return float(np.sqrt(out[4]))


def _in_pieces(cfg, rng, **capacities):
    run = Run(cfg, **capacities)
    sink = MemorySink()
    run.start(sink)
    while run.advance(sink, max_steps=int(rng.integers(1, 40))) != L.DONE:
        pass
    return sink.result(run), np.concatenate(sink._step)


def _same(a, b):
    np.testing.assert_array_equal(a.u_final, b.u_final)
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.u, b.u)
    np.testing.assert_array_equal(a.v, b.v)
    for name in a.diagnostics:
        np.testing.assert_array_equal(a.diagnostics[name], b.diagnostics[name])
    for name in a.bounces:
        np.testing.assert_array_equal(a.bounces[name], b.bounces[name])
    assert a.stats["steps"] == b.stats["steps"]
    assert a.stats["rejected_steps"] == b.stats["rejected_steps"]


@pytest.mark.parametrize("integrator", sorted(DENSE))
def test_a_run_cut_into_calls_and_small_buffers_is_bitwise_the_same(integrator, rng,
                                                                    monkeypatch):
    """Calls of 1–40 steps into buffers of 3 snapshots and 5 diagnostics rows, with steps
    allowed to cover at most 2 output times of each grid (FULL before many steps, many
    steps ended on an output time): the same steps and rows as one call into large
    buffers under the same rule."""
    from rodjit.driver import setup

    # the set-up keeps a run's control tuple by the configuration's values: forget it when
    # the constant it is built from changes
    monkeypatch.setattr(control, "DENSE_OUTPUTS_MAX", 2)
    setup.clear()
    cfg = _paper(integrator, **{"time.t_end": 0.6, "rod.mu": 0.5,
                                "output.diagnostics_interval": 0.002})
    one = _simulate(cfg)
    cut, _ = _in_pieces(cfg, rng, snapshot_capacity=3, diag_capacity=5, event_capacity=1)
    _same(one, cut)
    np.testing.assert_array_equal(cut.diagnostics["t"], np.arange(301) * 0.002)
    # without the rule's cut the run takes fewer steps: every output time was interpolated
    monkeypatch.undo()
    setup.clear()
    free = _simulate(cfg)
    assert free.stats["steps"] < one.stats["steps"]
    assert np.abs(free.diagnostics["u_bottom"] - one.diagnostics["u_bottom"]).max() < 1e-3


def test_requested_buffers_below_a_steps_outputs_are_enlarged():
    cfg = _paper("dp54", **{"output.diagnostics_interval": 1e-4})
    run = Run(cfg, snapshot_capacity=3, diag_capacity=5)
    assert run.arrays.snap_t.size == run.ctrl.dense_snapshots == control.DENSE_OUTPUTS_MAX
    assert run.arrays.diag.shape[0] == run.ctrl.dense_diagnostics == control.DENSE_OUTPUTS_MAX
    big = Run(cfg.override({"rod.N": 20_000}))        # the snapshot buffer's memory rule
    assert big.ctrl.dense_snapshots == big.arrays.snap_t.size < control.DENSE_OUTPUTS_MAX
    quiet = Run(cfg.override(QUIET), snapshot_capacity=1, diag_capacity=1)
    assert quiet.arrays.snap_t.size == quiet.arrays.diag.shape[0] == 1       # no outputs, no rows
    land = Run(cfg.override({"output.interpolate": False}), snapshot_capacity=3)
    assert land.arrays.snap_t.size == 3 and land.ctrl.dense_snapshots == 0


@pytest.mark.parametrize("integrator", sorted(DENSE))
def test_resume_from_a_checkpoint_is_bit_identical(integrator):
    cfg = _paper(integrator, **{"time.t_end": 0.6, "rod.mu": 0.2, "time.rtol": 1e-7})
    assert Run(cfg).ctrl.dense
    assert_resume_is_bit_identical(cfg, max_steps=57)


def test_an_interrupted_run_file_resumes_bit_for_bit(tmp_path, many_calls):
    """Through the HDF5 path: stopped at a compiled call, resumed from the file's
    checkpoint, the same file as an uninterrupted run."""
    import os
    import signal
    cfg = _paper("dp54", **{"rod.mu": 0.5})
    ref, cut = tmp_path / "ref.h5", tmp_path / "cut.h5"
    state = {"n": 0}

    def progress(run):
        state["n"] += 1
        if state["n"] == 3:
            os.kill(os.getpid(), signal.SIGINT)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelWarning)
        rodjit.run_to_file(cfg, ref)
        with pytest.raises(rodjit.RunInterrupted):
            rodjit.run_to_file(cfg, cut, progress=progress)
        assert rodjit.resume_file(cut).status == "completed"
    assert_same_files(cut, ref)


# ---- output.interpolate = false ----------------------------------------------------------
@pytest.mark.parametrize("integrator", sorted(DENSE))
def test_interpolate_false_lands_every_row_on_a_step(integrator):
    """Each snapshot is the state of the step that ends at its time: a run stopped there
    (time.t_end = that time) ends in it bit for bit, and every row has its own step.  With
    interpolation several rows share a step and are not a step's state."""
    cfg = _paper(integrator, **{"time.t_end": 0.4, "time.rtol": 1e-6, "time.atol": 1e-6})
    land = cfg.override({"output.interpolate": False})
    assert not Run(land).ctrl.dense
    run = Run(land)
    sink = MemorySink()
    run.start(sink)
    while run.advance(sink) != L.DONE:
        pass
    res = sink.result(run)
    steps = np.concatenate(sink._step)
    assert np.all(np.diff(steps) > 0)
    for k in (17, 40, 63):
        stopped = _simulate(land.override({"time.t_end": float(res.t[k])}))
        np.testing.assert_array_equal(stopped.u_final, res.u[k])
        np.testing.assert_array_equal(stopped.v_final, res.v[k])
    _, dense_steps = _in_pieces(cfg, np.random.default_rng(1))
    assert np.any(np.diff(dense_steps) == 0)


def test_control_says_when_the_loop_interpolates():
    for name in registry.NAMES:
        cfg = _cfg(name)
        assert Run(cfg).ctrl.dense is (name in DENSE)
        assert registry.get(name).dense is (name in DENSE)
    dp = _cfg("dp54")
    assert not Run(dp.override({"output.interpolate": False})).ctrl.dense
    assert not Run(dp.override({"time.dt": 1e-4})).ctrl.dense   # fixed steps land
    assert control.build(Config().time, Verlet(0.05), True).dense is False
    for params in (erk.DP54, erk.DOP853):
        assert registry.entry_of(params).work_rows == erk.work_rows(params)


# ---- the key -----------------------------------------------------------------------------
@pytest.mark.parametrize("value, message", [
    (1, "output.interpolate = 1 is not a boolean (true or false)"),
    ("maybe", "output.interpolate = 'maybe' is not a boolean (true or false)"),
    (np.float64(0.0), "output.interpolate = np.float64(0.0) is not a boolean"),
    (None, "output.interpolate must be set (true or false)"),
])
def test_a_bad_value_is_one_line_naming_the_key(value, message):
    with pytest.raises(ValueError) as info:
        Config().override({"output.interpolate": value})
    assert str(info.value).startswith(message) and "\n" not in str(info.value)


def test_the_key_reads_from_toml_and_the_command_line_form():
    assert Config().output.interpolate is True
    assert Config().override({"output.interpolate": "false"}).output.interpolate is False
    assert Config().override({"output.interpolate": np.bool_(False)}).output.interpolate is False
    assert Config.from_toml_string("[output]\ninterpolate = false\n").output.interpolate is False
    with pytest.raises(ValueError, match="output.interpolate = 'true' is a quoted boolean; "
                                         "write true without quotes"):
        Config.from_toml_string('[output]\ninterpolate = "true"\n')
    cfg = Config().override({"output.interpolate": False})
    assert Config.from_toml_string(cfg.commented_toml()) == cfg
    assert "interpolate = false" in cfg.to_toml()
    # a stored configuration written before the key existed ran with landing steps
    old = "\n".join(line for line in Config().to_toml().splitlines()
                    if not line.startswith("interpolate"))
    assert Config.from_stored_toml(old).output.interpolate is False
    assert Config.from_stored_toml(Config().to_toml()).output.interpolate is True


def test_snapshots_inside_a_step_that_ends_across_the_switch_keep_the_steps_accuracy():
    """On a stiff floor a pair's step may end a sliver inside contact; its snapshots come
    from its own continuous extension, not from the derivative the law gives the new state
    (which the next step takes): dop853 at rtol 1e-6 interpolated the velocities of nodes
    in contact 6.5e-3 of the impact speed off where its landing run is 3.8e-5 off."""
    base = rodjit.load_preset("paper-mu0").override({
        "rod.N": 20, "floor.kappa_b": 1e7, "floor.beta": 0.01, "time.t_end": 1.0,
        "output.diagnostics_interval": 0.0, "time.integrator": "dop853"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rodjit.config.ModelWarning)
        ref = rodjit.simulate(base.override({"time.rtol": 1e-12, "time.atol": 1e-12,
                                             "output.interpolate": False}))
        got = {interp: rodjit.simulate(base.override({"output.interpolate": interp}))
               for interp in (True, False)}
    speed = (2 * 9.81 * 1.0) ** 0.5
    err = {k: max(np.abs(r.u - ref.u).max(), np.abs(r.v - ref.v).max() / speed)
           for k, r in got.items()}
    assert err[False] < 1e-4
    assert err[True] < 2 * err[False]


@pytest.mark.parametrize("integrator", sorted(DENSE))
def test_the_dissipated_extension_takes_the_floors_damping(integrator):
    """In contact with the floor's damping and no viscosity, the extension of the
    dissipated energy is the floor's alone: 0 at θ = 0, the step's own increment at θ = 1,
    growing in between (the step is short next to the contact)."""
    over = {"rod.mu": 0.0, "floor.damping": 0.3, "initial.height": -0.005,
            "initial.velocity": -3.0}
    h = 1e-5
    thetas = (0.0, 0.25, 0.5, 0.75, 1.0)
    _, _, _, diss, step_diss = _one_step(integrator, h, thetas, **over)
    assert diss[0] == 0.0 and step_diss > 0.0
    assert abs(diss[-1] - step_diss) < 1e-13 * step_diss
    assert np.all(np.diff(diss) > 0), diss
