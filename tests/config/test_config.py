"""Configuration: defaults, files, and every class of bad input."""

from __future__ import annotations

import math

import pytest

from assembler_pin import AssemblerConfig, load_config
from assembler_pin.exceptions import ConfigError


def test_defaults_match_design_notes():
    cfg = load_config()
    assert cfg.platforms == 4 and cfg.gravity == 9.81
    assert cfg.plate.node_radius == 0.15 and cfg.plate.node_spacing_deg == 8.0
    assert (cfg.leg.min_length, cfg.leg.max_length) == (0.20, 0.35)
    assert (cfg.payload.mass, cfg.payload.offset) == (5.0, 0.2)
    # home SP height of the design notes: sqrt(0.275² − (2·0.15·sin 26°)²)
    expected = math.sqrt(0.275**2 - (2 * 0.15 * math.sin(math.radians(26))) ** 2)
    assert cfg.home_height == pytest.approx(expected, rel=1e-15)
    assert cfg.home_height == pytest.approx(0.2415, abs=1e-4)


def test_yaml_file_partial_keys_take_defaults(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("platforms: 2\nleg: {max_length: 0.4}\npayload: {mass: 1}\n")
    cfg = load_config(path)
    assert cfg.platforms == 2 and cfg.leg.max_length == 0.4 and cfg.leg.min_length == 0.2
    assert cfg.payload.mass == 1.0 and cfg.payload.offset == 0.2


@pytest.mark.parametrize(
    ("data", "needle"),
    [
        ({"platfroms": 3}, "unknown config key 'platfroms'"),
        ({"leg": {"max_lenght": 1}}, "unknown config key 'leg.max_lenght'"),
        ({"platforms": 0}, "platforms"),
        ({"platforms": 2.5}, "platforms"),
        ({"platforms": "four"}, "platforms"),
        ({"gravity": "9.81"}, "gravity"),
        ({"plate": {"node_radius": 0}}, "plate.node_radius"),
        ({"plate": {"node_radius": -0.1}}, "plate.node_radius"),
        ({"plate": {"mass": -1}}, "plate.mass"),
        ({"leg": {"motor_mass": -0.1}}, "leg.motor_mass"),
        ({"leg": {"min_length": -0.2}}, "leg.min_length"),
        ({"leg": {"min_length": 0.3, "max_length": 0.3}}, "leg.max_length"),
        ({"leg": {"min_length": 0.3, "max_length": 0.25}}, "leg.max_length"),
        ({"leg": {"max_deflection_deg": 95}}, "leg.max_deflection_deg"),
        ({"leg": {"max_tension": 0}}, "leg.max_tension"),
        ({"payload": {"mass": -5}}, "payload.mass"),
        ({"payload": "heavy"}, "payload"),
        ({"plate": {"node_radius": 0.5}}, "no home pose exists"),
        ({"leg": {"min_length": 0.06, "max_length": 0.1}}, "no home pose exists"),
        ({"gravity": float("nan")}, "gravity"),
    ],
)
def test_bad_config_names_the_key(data, needle):
    with pytest.raises(ConfigError) as info:
        load_config(data)
    assert needle in str(info.value)


def test_bad_files(tmp_path):
    with pytest.raises(ConfigError, match="cannot read config file"):
        load_config(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("platforms: [1, 2\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_config(bad)
    listy = tmp_path / "list.yaml"
    listy.write_text("- 1\n- 2\n")
    with pytest.raises(ConfigError, match="mapping"):
        load_config(listy)


def test_direct_construction_is_validated():
    with pytest.raises(ConfigError, match="platforms"):
        AssemblerConfig(platforms=-1)
    with pytest.raises(ConfigError, match="platforms"):
        AssemblerConfig(platforms=True)
