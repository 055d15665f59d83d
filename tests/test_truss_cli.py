"""The compliant truss at the command line: ``statics --stiffness`` and ``stiffness --scaling``."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

from assembler_pin.cli import main


def _strict(text: str) -> dict:
    return json.loads(text, parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))


def test_statics_stiffness_adds_the_blocks_of_stiffness_json(capsys):
    assert main(["statics", "--home", "--json"]) == 0
    plain = _strict(capsys.readouterr().out)
    assert "sag" not in plain and "stiffness" not in plain  # the contract without the flag is unchanged
    assert main(["statics", "--home", "--stiffness", "--json"]) == 0
    doc = _strict(capsys.readouterr().out)
    assert main(["stiffness", "--home", "--json"]) == 0
    alone = _strict(capsys.readouterr().out)
    assert {k: v for k, v in doc.items() if k not in ("sag", "stiffness")} == plain
    assert doc["stiffness"] == alone and doc["sag"] == alone["sag"]
    assert doc["sag"]["translation"][2] < -5e-5  # the home pose sags down, about 0.06 mm
    assert main(["statics", "--home", "--stiffness"]) == 0
    text = capsys.readouterr().out
    assert "weakest" in text and "sag: translation" in text


def test_statics_stiffness_of_a_singular_pose_is_answered_as_none(capsys, tmp_path, am):
    turned = [pin.SE3.Identity()]
    for _ in range(am.n):
        turned.append(turned[-1] * pin.SE3(pin.exp3(np.array([0, 0, np.pi / 2])), np.array([0, 0, 0.24])))
    plates = tmp_path / "p.json"
    plates.write_text(json.dumps({"plates": [p.homogeneous.tolist() for p in turned]}))
    assert main(["statics", "--plates", str(plates), "--stiffness", "--json"]) == 1  # answered: there is none
    doc = _strict(capsys.readouterr().out)
    assert doc["stiffness"]["success"] is False and doc["sag"]["translation"][0] is None
    assert len(doc["forces"]) == am.n  # the statics are still answered


def test_statics_stiffness_with_a_carrier_is_refused_in_one_line(capsys):
    assert main(["statics", "--home", "--stiffness", "--carrier", "ur5", "--json"]) == 2
    out, err = capsys.readouterr()
    assert not out and len(err.strip().splitlines()) == 1 and "--stiffness" in err
