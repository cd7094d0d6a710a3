"""Calibration against a table of drops: the stated confidence intervals contain the true
parameters as often as they say (synthetic tables: known parameters plus Gaussian noise,
fixed seeds, judged by a binomial acceptance band), and a comparison of laws names the
law that made the table."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import rodjit
from rodjit.analysis import compare_laws, fit_table
from rodjit.analysis.evaluate import evaluate
from rodjit.analysis.fit_table import TableFit, t_quantile
from rodjit.cli import main

# drops of the paper's rod at impact speeds 2–8 m/s: restitution and contact time, with
# the errors of a drop test (2e-3 in restitution, 0.1 ms in contact time)
BASE = rodjit.load_preset("paper-mu100").override({"time.t_end": 1.0,
                                                   "initial.height": 0.01})
SPEEDS = (2.0, 3.0, 4.0, 5.0, 6.0, 8.0)
TRUTH = {"rod.mu": 150.0, "floor.kappa_b": 2000.0}
START = {"rod.mu": 120.0, "floor.kappa_b": 1500.0}
SIGMA = {"restitution_first": 2e-3, "contact_time_first": 1e-4}
KEYS = list(TRUTH)


def _exact(cfg) -> list[dict]:
    return evaluate([cfg.override({"initial.impact_speed": v}) for v in SPEEDS],
                    scheduler="inline", columns=list(SIGMA))


def _noisy(exact, rng, speeds=SPEEDS, sigma=SIGMA) -> list[dict]:
    """The rows of a synthetic table: the exact values at ``speeds`` plus Gaussian errors
    of the standard deviations ``sigma``, given in the table as its uncertainties."""
    rows = []
    for v, r in zip(speeds, exact):
        row = {"initial.impact_speed": v}
        for name, s in sigma.items():
            row[name] = r[name] + s * rng.standard_normal()
            row[f"sigma_{name}"] = s
        rows.append(row)
    return rows


def _binomial_band(n: int, p: float = 0.95, tail: float = 5e-4) -> tuple[int, int]:
    """The counts k with P(X < k) and P(X > k) both above ``tail`` for X ~ B(n, p)."""
    pmf = [math.comb(n, k) * p ** k * (1 - p) ** (n - k) for k in range(n + 1)]
    cdf = np.cumsum(pmf)
    lo = int(np.searchsorted(cdf, tail))
    hi = int(np.searchsorted(cdf, 1 - tail))
    return lo, hi


def _coverage(draws: int, seed: int) -> tuple[dict, list[TableFit]]:
    exact = _exact(BASE.override(TRUTH))
    rng = np.random.default_rng(seed)
    hits = {k: 0 for k in KEYS}
    fits = []
    for _ in range(draws):
        f = fit_table(KEYS, _noisy(exact, rng), BASE, start=START, scheduler="inline")
        assert f.converged and f.weighted and f.dof == 2 * len(SPEEDS) - len(KEYS)
        for k, (lo, hi) in f.intervals(0.95).items():
            hits[k] += lo <= TRUTH[k] <= hi
        fits.append(f)
    return hits, fits


def test_t_quantile_is_scipys():
    stats = pytest.importorskip("scipy.stats")
    for dof in (1, 2, 3, 4, 5, 8, 13, 40, 101):
        for level in (0.5, 0.9, 0.95, 0.99, 0.999):
            assert t_quantile(level, dof) == pytest.approx(stats.t.ppf(0.5 + level / 2, dof),
                                                           rel=1e-9)


def test_intervals_are_normal_with_known_errors_and_student_t_without():
    f = TableFit(["a"], [1.0], [0.1], [[0.01]], [], 3.0, 1, 1, True, weighted=True, dof=3)
    assert f.intervals(0.95)["a"] == pytest.approx((1 - 0.1 * 1.959964, 1 + 0.1 * 1.959964))
    f.weighted = False
    assert f.intervals(0.95)["a"] == pytest.approx((1 - 0.1 * 3.182446, 1 + 0.1 * 3.182446))
    with pytest.raises(ValueError, match="level = 1.5 is out of range"):
        f.intervals(1.5)


def test_stated_95_percent_intervals_cover_the_truth_on_noisy_tables():
    """12 noisy tables (fixed seed): each key's 95 % interval holds its true value in a
    count inside the binomial band of 12 draws, and no fit lands beyond 4 errors."""
    hits, fits = _coverage(12, seed=20261207)
    lo, hi = _binomial_band(12)
    for k in KEYS:
        assert lo <= hits[k] <= hi, (k, hits[k], (lo, hi))
    for f in fits:
        for k, v, e in zip(f.keys, f.values, f.errors):
            assert abs(v - TRUTH[k]) < 4 * e, (k, v, e)


@pytest.mark.slow
def test_coverage_over_200_noisy_tables_is_inside_the_binomial_band():
    hits, fits = _coverage(200, seed=7)
    lo, hi = _binomial_band(200)
    for k in KEYS:
        assert lo <= hits[k] <= hi, (k, hits[k], (lo, hi))
    # the errors stated are the spread of the answers (within the sampling error of 200)
    for j, k in enumerate(KEYS):
        spread = float(np.std([f.values[j] for f in fits], ddof=1))
        stated = float(np.median([f.errors[j] for f in fits]))
        assert 0.8 < spread / stated < 1.2, (k, spread, stated)


def test_a_comparison_names_the_setting_that_made_the_table():
    """Two candidates, the paper's floor (β = 0.05) and a softer one (β = 0.2), each
    fitting μ and κ_b: on a table made with the first, the first wins by far."""
    rows = _noisy(_exact(BASE.override(TRUTH)), np.random.default_rng(1))
    c = compare_laws(rows, {"beta 0.05": (BASE, KEYS, START),
                            "beta 0.2": (BASE.override({"floor.beta": 0.2}), KEYS, START)},
                     scheduler="inline")
    assert c.best == "beta 0.05" and c.ranking() == ["beta 0.05", "beta 0.2"]
    assert c.aic("beta 0.2") - c.aic("beta 0.05") > 10
    assert "beta 0.05: chi2 = " in repr(c).splitlines()[1]
    with pytest.raises(ValueError, match="candidate 'x': give"):
        compare_laws(rows, {"x": (BASE,)})
    with pytest.raises(ValueError, match="candidate 'y': .*rod.law"):
        compare_laws(rows, {"y": (BASE, ["rod.law"])})


@pytest.mark.slow
def test_a_comparison_of_stress_laws_names_the_law_that_made_the_table():
    """The log law of tests/custom_law.py against Aiki–Kosugi's at μ = 1 (where their
    contact times differ by 15 %), each fitting μ and κ: the law that made the table
    wins, both ways."""
    sys.path.insert(0, str(Path(__file__).parent))
    import custom_law  # noqa: F401  (registers "log-test")

    base = BASE.override({"time.t_end": 1.5, "rod.mu": 1.0})
    keys, start = ["rod.mu", "rod.kappa"], {"rod.mu": 1.2, "rod.kappa": 110.0}
    sigma = {"restitution_first": 2e-3, "contact_time_first": 1e-3}
    rng = np.random.default_rng(3)
    for law in ("log-test", "aiki-kosugi"):
        made = base.override({"rod.law": law})
        exact = evaluate([made.override({"initial.impact_speed": v}) for v in SPEEDS],
                         scheduler="inline", columns=list(sigma))
        rows = [{"initial.impact_speed": v,
                 **{n: r[n] + s * rng.standard_normal() for n, s in sigma.items()},
                 **{f"sigma_{n}": s for n, s in sigma.items()}}
                for v, r in zip(SPEEDS, exact)]
        c = compare_laws(rows, {"aiki-kosugi": (base, keys, start),
                                "log-test": (base.override({"rod.law": "log-test"}), keys,
                                             start)}, scheduler="inline")
        assert c.best == law, repr(c)
        other = "aiki-kosugi" if law == "log-test" else "log-test"
        assert c.aic(other) - c.aic(law) > 10


@pytest.mark.parametrize("cell, words", [
    ("nan", "row 1: restitution_first = nan is out of range (a finite number)"),
    ("inf", "row 1: restitution_first = inf is out of range"),
])
def test_a_table_with_a_non_finite_value_exits_2_naming_row_and_column(tmp_path, cell,
                                                                        words):
    path = tmp_path / "drops.csv"
    path.write_text("initial.impact_speed,restitution_first,contact_time_first\n"
                    f"2,{cell},0.0123\n4,0.12,0.0121\n")
    with pytest.raises(ValueError, match="out of range"):
        fit_table(KEYS, path, BASE, scheduler="inline")
    res = CliRunner().invoke(main, ["fit", "rod.mu,floor.kappa_b", "paper-mu100",
                                    "--table", str(path), "--scheduler", "inline"])
    assert res.exit_code == 2, res.output
    assert words in res.output and len(res.output.strip().splitlines()) == 1


def test_too_few_rows_for_the_keys_exit_2(tmp_path):
    path = tmp_path / "drops.csv"
    path.write_text("initial.impact_speed,restitution_first\n2,0.12\n")
    res = CliRunner().invoke(main, ["fit", "rod.mu,floor.kappa_b", "paper-mu100",
                                    "--table", str(path), "--scheduler", "inline"])
    assert res.exit_code == 2
    assert "holds 1 measurement for 2 keys (rod.mu, floor.kappa_b): it needs at least 2" in res.output
    assert len(res.output.strip().splitlines()) == 1


def test_the_command_ranks_candidates_and_prints_intervals(tmp_path):
    rows = _noisy(_exact(BASE.override(TRUTH)), np.random.default_rng(2))
    path = tmp_path / "drops.csv"
    names = list(rows[0])
    path.write_text(",".join(names) + "\n" + "".join(
        ",".join(repr(float(r[n])) for n in names) + "\n" for r in rows))
    sets = ["--set", "time.t_end=1", "--set", "initial.height=0.01", "--set", "rod.mu=120",
            "--set", "floor.kappa_b=1500", "--scheduler", "inline"]
    res = CliRunner().invoke(main, ["fit", "rod.mu,floor.kappa_b", "paper-mu100", *sets,
                                    "--table", str(path), "--compare", "floor.beta=0.2,0.05"])
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    assert lines[0].startswith("LawComparison")
    assert lines[1].startswith("  floor.beta = 0.05: chi2 = ") and "ΔAIC = 0;" in lines[1]
    assert any(ln.startswith("floor.beta = 0.05: 95 % intervals: rod.mu in [") for ln in lines)
    one = CliRunner().invoke(main, ["fit", "rod.mu,floor.kappa_b", "paper-mu100", *sets,
                                    "--table", str(path)])
    assert one.exit_code == 0, one.output
    (lo, hi), = [tuple(float(x) for x in ln.split("rod.mu in [")[1].split("]")[0].split(","))
                 for ln in one.output.splitlines() if ln.startswith("95 % intervals:")]
    assert lo < TRUTH["rod.mu"] < hi
    bad = CliRunner().invoke(main, ["fit", "rod.mu", "paper-mu100", "--target",
                                    "restitution_first=0.5", "--compare", "floor.beta=0.1"])
    assert bad.exit_code == 2 and "--compare ranks fits to a table" in bad.output
