"""Configuration: defaults, TOML round trip, overrides, and one-line errors for bad input."""
import math

import pytest

from rodjit import Config
from rodjit.config import parse_value, valid_keys
from rodjit.presets import load_preset, preset_names


def test_defaults_are_the_paper_first_figure():
    c = Config()
    assert (c.rod.N, c.rod.kappa, c.rod.gamma, c.rod.mu) == (5, 100.0, 0.0, 0.0)
    assert (c.floor.kappa_b, c.floor.beta, c.gravity.g) == (1000.0, 0.05, -9.81)
    assert (c.initial.height, c.initial.velocity, c.initial.strain) == (1.0, 0.0, 0.0)
    assert c.time.t_end == 5.0 and c.time.integrator == "auto" and c.time.dt is None
    assert c.time.control == "tolerance"
    assert c.output.snapshot_interval == 0.005


def test_toml_round_trip(tmp_path):
    c = Config().override({"rod.mu": 100.0, "time.dt_max": 1e-3, "time.integrator": "semi-implicit"})
    p = tmp_path / "c.toml"
    p.write_text(c.to_toml())
    assert Config.from_toml(p) == c


def test_override_returns_new_config_and_parses_strings():
    c = Config()
    d = c.override({"rod.mu": "12.5", "rod.N": "7", "time.dt": "none", "time.integrator": "'energy'"})
    assert c.rod.mu == 0.0 and d.rod.mu == 12.5 and d.rod.N == 7 and d.time.dt is None
    assert d.time.integrator == "energy"
    assert Config.from_dict({"rod": {"mu": 3.0}, "floor.beta": 0.1}).floor.beta == 0.1


def test_presets_ship_the_paper_settings():
    assert {"paper-mu0", "paper-mu100"} <= set(preset_names())
    a, b = load_preset("paper-mu0"), load_preset("paper-mu100")
    assert (a.rod.N, a.rod.gamma, a.rod.mu) == (5, 0.0, 0.0)
    assert (b.rod.N, b.rod.gamma, b.rod.mu) == (5, 0.0, 100.0)
    with pytest.raises(ValueError, match="unknown preset 'nope'.*paper-mu0"):
        load_preset("nope")


@pytest.mark.parametrize("key, value, pattern", [
    ("rod.N", 0, r"rod\.N = 0 is out of range \(int in \[1, 10000000\]\)"),
    ("rod.N", 2.5, r"rod\.N = 2\.5 is not an integer"),
    ("rod.kappa", 0.0, r"rod\.kappa = 0\.0 is out of range \(float > 0\)"),
    ("rod.kappa", -1.0, r"rod\.kappa = -1\.0 is out of range"),
    ("rod.mu", -1e-3, r"rod\.mu = -0\.001 is out of range \(float >= 0\)"),
    ("rod.gamma", math.nan, r"rod\.gamma = nan is not finite"),
    ("floor.beta", 0.0, r"floor\.beta = 0\.0 is out of range \(float > 0\)"),
    ("floor.kappa_b", math.inf, r"floor\.kappa_b = inf is not finite"),
    ("gravity.g", "abc", r"gravity\.g = 'abc' is not a number"),
    ("gravity.g", True, r"gravity\.g = True is not a number"),
    ("initial.strain", -1.0, r"initial\.strain = -1\.0 is out of range \(float > -1\)"),
    ("initial.height", -0.06, r"initial\.height = -0\.06 is out of range \(float > -floor\.beta = -0\.05"),
    ("time.cfl", 1.5, r"time\.cfl = 1\.5 is out of range \(float in \(0, 1\]\)"),
    ("time.t_end", 0.0, r"time\.t_end = 0\.0 is out of range"),
    ("time.integrator", "rk4", r"time\.integrator = 'rk4' is not allowed \(one of 'auto', 'verlet', 'semi-implicit', 'energy', 'dp54', 'dop853', 'radau5'\)"),
    ("time.dt", -1.0, r"time\.dt = -1\.0 is out of range"),
    ("time.dt_min", 1.0, r"time\.dt_min = 1\.0 is out of range \(float > 0 and < time\.dt_max"),
    ("output.snapshot_interval", -1.0, r"output\.snapshot_interval = -1\.0 is out of range"),
    ("rod.law", "hooke", r"rod\.law = 'hooke' is not a known rod law; choose one of \[.*'aiki-kosugi'.*\]"),
])
def test_bad_values_name_field_and_range(key, value, pattern):
    over = {key: value}
    if key == "time.dt_min":
        over["time.dt_max"] = 0.5
    with pytest.raises(ValueError, match=pattern) as exc:
        Config().override(over)
    assert "\n" not in str(exc.value)


def test_unknown_key_suggests_close_match_and_lists_keys():
    with pytest.raises(ValueError, match=r"unknown configuration key 'rod\.mew'; did you mean 'rod\.mu'\? valid keys: rod\.N, ") as exc:
        Config().override({"rod.mew": 1.0})
    assert "floor.kappa_b" in str(exc.value)
    with pytest.raises(ValueError, match=r"did you mean 'floor\.kappa_b'"):
        Config().override({"rod.kappa_b": 1.0})
    with pytest.raises(ValueError, match=r"unknown configuration section \[flor\]; did you "
                                         r"mean \[floor\]\? sections: \[rod\], \[floor\]"):
        Config.from_dict({"flor": {"beta": 1.0}})


def test_toml_file_errors(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        Config.from_toml(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[rod\nN = 5")
    with pytest.raises(ValueError, match="is not valid TOML"):
        Config.from_toml(bad)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text("[rod]\nkapa = 5.0\n")
    with pytest.raises(ValueError, match="did you mean 'rod.kappa'"):
        Config.from_toml(unknown)


def test_parse_value():
    assert parse_value("k", "1e-3") == 1e-3
    assert parse_value("k", "none") is None
    assert parse_value("k", "[1, 2]") == [1, 2]
    assert parse_value("k", "verlet") == "verlet"


def test_valid_keys_cover_the_contract():
    keys = set(valid_keys())
    for k in ["rod.N", "rod.kappa", "rod.gamma", "rod.mu", "floor.kappa_b", "floor.beta",
              "gravity.g", "initial.height", "initial.velocity", "initial.strain",
              "time.t_end", "time.integrator", "time.cfl", "time.dt_max", "time.dt_min",
              "time.dt", "output.snapshot_interval", "output.diagnostics_interval"]:
        assert k in keys


@pytest.mark.parametrize("text, line, message", [
    ("[rod]\nN = 5\n\n[flor]\nkappa_b = 1000\n", 4,
     "unknown configuration section [flor]; did you mean [floor]?"),
    ("[floor]\nbeta = 0.05\nkapa_b = 1000\n", 3,
     "unknown configuration key 'floor.kapa_b'; did you mean 'floor.kappa_b'?"),
    ("# a comment\n[time]\nt_end = -1.0\n", 3, "time.t_end = -1.0 is out of range"),
    ("rod.mu = 1.0\nfloor.kappa_b = \"1e3 N\"\n", 2,
     "floor.kappa_b = '1e3 N' is not a number: values are plain SI numbers without units"),
    ("[rod]\n  'mu' = -3.0\n", 2, "rod.mu = -3.0 is out of range"),
], ids=["section", "key", "range", "unit", "quoted"])
def test_a_toml_error_names_the_file_and_line(tmp_path, text, line, message):
    path = tmp_path / "mine.toml"
    path.write_text(text)
    with pytest.raises(ValueError) as exc:
        Config.from_toml(path)
    assert str(exc.value).startswith(f"{path}, line {line}: {message}"), str(exc.value)


def test_a_value_with_a_unit_says_values_are_si_numbers():
    """``--set time.t_end=2s``: the values are plain SI numbers (docs/units.md)."""
    with pytest.raises(ValueError, match=r"^time\.t_end = '2s' is not a number: values are "
                                         r"plain SI numbers without units; write it in s, "
                                         r"without the unit \(see docs/units\.md; float > 0\)$"):
        Config().override({"time.t_end": "2s"})
    with pytest.raises(ValueError, match=r"write it in m, without the unit"):
        Config().override({"floor.beta": "5 mm"})
    with pytest.raises(ValueError, match=r"it is dimensionless"):
        Config().override({"rod.N": "50 segments"})
    with pytest.raises(ValueError, match=r"^rod\.mu = 'fast' is not a number \(float >= 0\)$"):
        Config().override({"rod.mu": "fast"})          # no number: no unit hint


@pytest.mark.parametrize("changes,warned", [
    ({"gravity.g": 9.81}, "gravity.g = 9.81 > 0 pulls the rod up"),
    ({"gravity.g": 9.81, "initial.velocity": -1.0}, "gravity.g = 9.81 > 0 pulls the rod up"),
    ({"floor.beta": 50.0}, "floor.beta = 50.0 puts the floor's bending limit"),
    ({"floor.beta": 1.0}, "floor.beta = 1.0 puts the floor's bending limit"),
], ids=["g up", "g up, too slow down", "beta 50", "beta 1"])
def test_a_set_up_that_is_surely_a_mistake_warns(changes, warned):
    """``gravity.g = +9.81`` (the rod flies up: "no impact") and ``floor.beta = 50`` (a
    bending limit 50 rod lengths deep) were accepted without a word."""
    cfg = Config().override({"rod.mu": 1.0, **changes})
    said = [w for w in cfg.warnings() if w.startswith(warned)]
    assert len(said) == 1, cfg.warnings()


@pytest.mark.parametrize("changes", [{}, {"gravity.g": 0.0}, {"floor.beta": 0.5},
                                     {"gravity.g": 9.81, "initial.velocity": -5.0},
                                     {"gravity.g": 1.0, "initial.height": -0.01}],
                         ids=["default", "free rod", "beta 0.5", "thrown down", "in contact"])
def test_a_set_up_that_reaches_the_floor_says_nothing(changes):
    assert Config().override({"rod.mu": 1.0, **changes}).warnings() == ()
