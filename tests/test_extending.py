"""The extension points of docs/extending.md, exercised from outside the package: the
floor law and the integrator of examples/extending/, registered by their own modules,
from Python and from the command line (``rodjit --import``), in a single run and in a
sweep whose worker processes import them."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import rodjit
from conftest import one_line, rodjit_cli

HERE = Path(__file__).resolve().parent.parent / "examples" / "extending"


@pytest.fixture
def extending(monkeypatch):
    """The example modules importable, as a user's own modules are from their folder."""
    monkeypatch.syspath_prepend(str(HERE))


def test_the_floor_law_is_a_consistent_singular_law(extending):
    """Its derivative is the slope of its value, its primitive's slope is its value (zero
    at 0), it pushes (≥ 0) below the surface and nothing above, and its barrier is −β."""
    import square_floor
    from rodjit import laws

    p = square_floor.SquareFloor(kappa_b=100.0, beta=0.05)
    assert laws.get_law("floor", "square-floor") is square_floor.LAW
    assert laws.lower(p) == -0.05
    h = np.linspace(-0.049, -1e-3, 40)
    step = 1e-7
    slope = [(laws.value(x + step, p) - laws.value(x - step, p)) / (2 * step) for x in h]
    np.testing.assert_allclose(slope, [laws.deriv(x, p) for x in h], rtol=1e-6)
    slope = [(laws.primitive(x + step, p) - laws.primitive(x - step, p)) / (2 * step)
             for x in h]
    np.testing.assert_allclose(slope, [laws.value(x, p) for x in h], rtol=1e-6)
    assert all(laws.value(x, p) > 0 for x in h) and laws.primitive(0.0, p) == 0.0
    assert laws.value(0.01, p) == laws.deriv(0.01, p) == laws.primitive(0.01, p) == 0.0
    # the surface stiffness 2κ_b/β (the built-in law's exponent 3 gives 3κ_b/β)
    assert laws.deriv(0.0, p) == pytest.approx(-2 * 100.0 / 0.05)
    assert math.isinf(laws.value(-0.05 + 1e-300, p)) or laws.value(-0.05 + 1e-12, p) > 1e12


def test_import_registers_what_a_module_defines_and_refuses_one_that_fails(tmp_path):
    p = rodjit_cli("--import", "square_floor", "config", "--set", "floor.law=square-floor",
                   cwd=HERE)
    assert p.returncode == 0, p.stderr
    assert 'law = "square-floor"' in p.stdout
    # without it the law is unknown, in one line naming the key
    p = rodjit_cli("config", "--set", "floor.law=square-floor", cwd=HERE)
    assert p.returncode == 2 and "square-floor" in one_line(p.stderr)
    p = rodjit_cli("--import", "no_such_module", "run", "--dry-run", cwd=tmp_path)
    assert p.returncode == 2
    assert one_line(p.stderr) == ("Error: --import no_such_module: ModuleNotFoundError: No "
                                  "module named 'no_such_module'")
    (tmp_path / "broken.py").write_text("raise RuntimeError('broken on purpose')\n")
    p = rodjit_cli("--import", "broken", "run", "--dry-run", cwd=tmp_path)
    assert p.returncode == 2
    assert one_line(p.stderr) == "Error: --import broken: RuntimeError: broken on purpose"


def test_a_sweeps_workers_import_the_modules_of_its_law_and_integrator(extending):
    import position_verlet  # noqa: F401
    import square_floor  # noqa: F401
    from rodjit.sweeps.point import user_modules

    cfg = rodjit.Config().override({"floor.law": "square-floor",
                                    "time.integrator": "position-verlet"})
    assert user_modules(cfg) == ("square_floor", "position_verlet")
    assert user_modules(rodjit.Config()) == ()


@pytest.mark.slow      # compiles the loop for the new floor law (a new parameter type)
def test_the_floor_law_runs_and_sweeps_from_the_command_line(extending, tmp_path):
    """The energy integrator keeps the energy to rounding with the new law (its discrete
    gradient uses the law's primitive: a primitive that did not match the value would show
    here), and a two-process sweep's workers find the law by importing its module."""
    import square_floor  # noqa: F401  (the files name the law: reading them needs it)

    args = ("paper-mu0", "--set", "floor.law=square-floor", "--set", "time.t_end=1",
            "--set", "time.integrator=energy")
    p = rodjit_cli("--import", "square_floor", "run", *args, "-o", tmp_path / "r.h5",
                   cwd=HERE, timeout=900)
    assert p.returncode == 0, p.stderr
    r = rodjit.load_file(tmp_path / "r.h5")
    assert r.n_bounces >= 1 and r.energy_error() < 1e-10
    p = rodjit_cli("--import", "square_floor", "sweep", *args, "--grid",
                   "floor.kappa_b=500,1000", "--jobs", "2", "-o", tmp_path / "s.h5", cwd=HERE,
                   timeout=900)
    assert p.returncode == 0, p.stderr
    table = rodjit.load_sweep(tmp_path / "s.h5")
    assert list(table["status"]) == ["completed", "completed"]
    assert table["restitution_first"][1] == r.impact()["restitution_first"]


@pytest.mark.slow      # compiles the loop for the new integrator
def test_the_integrator_converges_at_second_order_and_sweeps(extending, tmp_path):
    """Position Verlet at fixed steps on the free vibration of a pre-strained rod (no
    floor, no gravity): the error at t = 0.3 falls fourfold per halving of dt."""
    import position_verlet  # noqa: F401  (registers the integrator)

    free = rodjit.Config().override({"gravity.g": 0.0, "initial.height": 1.0,
                                     "initial.strain": 0.05, "time.t_end": 0.3,
                                     "output.times": [0.3]})
    ref = rodjit.simulate(free.override({"time.integrator": "radau5", "time.rtol": 1e-12,
                                         "time.atol": 1e-12}))
    errors = []
    for dt in (1e-3, 5e-4, 2.5e-4):
        r = rodjit.simulate(free.override({"time.integrator": "position-verlet",
                                           "time.control": "cfl", "time.dt": dt}))
        errors.append(np.max(np.abs(r.u[-1] - ref.u[-1])))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.2), (errors, orders)
    p = rodjit_cli("--import", "position_verlet", "sweep", "--set",
                   "time.integrator=position-verlet", "--set", "time.control=cfl", "--set",
                   "time.t_end=0.6", "--grid", "rod.mu=0,1", "--jobs", "2", "-o",
                   tmp_path / "s.h5", cwd=HERE, timeout=900)
    assert p.returncode == 0, p.stderr
    table = rodjit.load_sweep(tmp_path / "s.h5")
    assert list(table["status"]) == ["completed", "completed"]
    assert sys.modules["position_verlet"].SCHEME.name == "position-verlet"
