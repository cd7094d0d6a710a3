"""The field specs as one source: every key's meaning and unit, ``rodjit config`` (commented
TOML that reads back, ``--keys``), strict TOML files, NumPy numbers."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rodjit import presets
from rodjit.config import Config, field_spec, key_lines, valid_keys

from conftest import rodjit_cli


def test_every_key_has_a_meaning_and_a_unit_or_is_text():
    for key in valid_keys():
        spec = field_spec(key)
        assert spec.meaning, key
        assert bool(spec.unit) == (spec.kind not in ("str", "bool")), key


@pytest.mark.parametrize("source", [None, *presets.preset_names()])
def test_commented_toml_reads_back(source):
    cfg = Config() if source is None else presets.load_preset(source)
    cfg = cfg.override({"time.dt": 2e-4, "rod.mu": 3.5})
    text = cfg.commented_toml()
    assert Config.from_toml_string(text) == cfg
    lines = text.splitlines()
    for key in valid_keys():              # every key, each after its comment
        section, name = key.split(".")
        start = lines.index(f"[{section}]")
        i = next(j for j, line in enumerate(lines) if j > start and (
            line.startswith(f"{name} = ") or line == f"# {name} is unset"))
        assert lines[i - 1].startswith(f"# {field_spec(key).meaning}"), key


def test_each_key_is_commented_with_meaning_unit_default_and_range():
    text = Config().override({"rod.mu": 7.0}).commented_toml().splitlines()
    i = text.index("mu = 7.0")
    assert text[i - 1] == ("# viscosity mu of the rod; unit N s; default 0.0; float >= 0")
    i = text.index("# dt is unset")
    assert "fixed time step; unit s; default unset; float > 0" in text[i - 1]
    i = text.index(f'integrator = "{Config().time.integrator}"')
    assert "one of 'auto', 'verlet'" in text[i - 1]


def test_defaults_in_comments_come_from_the_dataclasses():
    text = Config().override({"rod.N": 9}).commented_toml()
    assert f"default {Config().rod.N};" in text
    assert "N = 9" in text


def test_cli_config_prints_the_resolved_configuration(tmp_path):
    r = rodjit_cli("config", "paper-mu100", "--set", "rod.N=8", "--set", "time.dt=1e-4")
    assert r.returncode == 0, r.stderr
    cfg = Config.from_toml_string(r.stdout)
    assert cfg == presets.load_preset("paper-mu100").override({"rod.N": 8, "time.dt": 1e-4})
    (tmp_path / "c.toml").write_text(r.stdout)
    again = rodjit_cli("config", str(tmp_path / "c.toml"))
    assert again.returncode == 0 and again.stdout == r.stdout


def test_cli_config_keys_lists_every_key():
    r = rodjit_cli("config", "--keys")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert [line.split()[0] for line in lines] == valid_keys()
    assert lines == key_lines()
    assert any(line.startswith("rod.mu ") and "viscosity" in line and "[N s]" in line
               for line in lines)


def test_cli_config_errors_name_the_key(tmp_path):
    r = rodjit_cli("config", "--set", "rod.N=0")
    assert r.returncode == 2 and "rod.N = 0 is out of range (int in [1, 10000000])" in r.stderr
    (tmp_path / "q.toml").write_text('[rod]\nkappa = "100"\n')
    r = rodjit_cli("config", str(tmp_path / "q.toml"))
    assert r.returncode == 2
    assert "rod.kappa = '100' is a quoted number; write 100 without quotes" in r.stderr


@pytest.mark.parametrize("text, message", [
    ('[rod]\nkappa = "100"\n', "rod.kappa = '100' is a quoted number; write 100 without quotes"),
    ('[rod]\nN = "7"\n', "rod.N = '7' is a quoted number; write 7 without quotes"),
    ('[time]\ndt = "1e-4"\n', "time.dt = '1e-4' is a quoted number; write 1e-4 without quotes"),
    ('[rod]\nmu = "much"\n', "rod.mu = 'much' is not a number"),
    ('[rod]\nmu = true\n', "rod.mu = True is not a number"),
])
def test_toml_files_are_strict(tmp_path, text, message):
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("(", r"\(")):
        Config.from_toml_string(text)
    (tmp_path / "c.toml").write_text(text)
    with pytest.raises(ValueError, match=message.split(" is ")[0]):
        Config.from_toml(tmp_path / "c.toml")


def test_override_still_parses_command_line_strings():
    cfg = Config().override({"rod.mu": "1e-3", "rod.N": "7", "time.integrator": "'energy'",
                             "time.dt": "none"})
    assert (cfg.rod.mu, cfg.rod.N, cfg.time.integrator, cfg.time.dt) == (1e-3, 7, "energy",
                                                                         None)


@pytest.mark.parametrize("value", [np.int64(7), np.int32(7), np.uint8(7), np.float64(7.0)])
def test_numpy_integers_are_integers(value):
    cfg = Config().override({"rod.N": value})
    assert cfg.rod.N == 7 and type(cfg.rod.N) is int


@pytest.mark.parametrize("value", [np.float64(0.25), np.float32(0.25), np.int64(2)])
def test_numpy_numbers_are_numbers(value):
    cfg = Config().override({"rod.mu": value})
    assert cfg.rod.mu == float(value) and type(cfg.rod.mu) is float
    assert Config.from_toml_string(cfg.to_toml()) == cfg        # written as plain TOML


@pytest.mark.parametrize("key, value, message", [
    ("rod.N", np.bool_(True), "rod.N = np.True_ is not an integer"),
    ("rod.mu", np.bool_(False), "rod.mu = np.False_ is not a number"),
    ("rod.N", np.float64(7.5), "rod.N = np.float64(7.5) is not an integer"),
    ("rod.mu", np.float64(-1.0), "rod.mu = -1.0 is out of range (float >= 0)"),
    ("rod.mu", np.float64("nan"), "rod.mu = nan is not finite"),
])
def test_numpy_values_are_checked_and_errors_name_the_key(key, value, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        Config().override({key: value})


def test_specs_cover_every_dataclass_field():
    cfg = Config()
    names = [f"{s}.{f.name}" for s in cfg.to_dict()
             for f in dataclasses.fields(getattr(cfg, s))]
    assert names == valid_keys()
