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
    # the plain answer comes from the Pinocchio-free home path (held to the full path in test_startup.py)
    statics_part = {k: v for k, v in doc.items() if k not in ("sag", "stiffness")}
    assert statics_part.keys() == plain.keys()
    for key, value in plain.items():
        if isinstance(value, (bool, str)) or value is None or key == "violations":
            assert statics_part[key] == value, key
        elif key == "clearance":  # the closest pair: the same two bodies, the same distance
            assert statics_part[key]["between"] == value["between"]
            assert statics_part[key]["min_distance_m"] == pytest.approx(value["min_distance_m"], abs=1e-9)
        else:
            # deflections at home are 0 to rounding: arccos near 1 turns one ulp into ~1e-6°
            atol = 1e-5 if key == "deflection_deg" else 1e-9
            np.testing.assert_allclose(statics_part[key], value, rtol=1e-12, atol=atol, err_msg=key)
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


def test_stiffness_scaling_json_and_figure_are_the_full_models_stiffness(capsys, tmp_path):
    import assembler_pin as ap
    from assembler_pin.compliance.ee_stiffness import elastic_compliance

    out = tmp_path / "scaling.png"
    assert main(["stiffness", "--scaling", "--max-platforms", "3", "--out", str(out), "--json"]) == 0
    doc = _strict(capsys.readouterr().out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and doc["out"] == str(out)
    assert doc["platforms"] == [1, 2, 3] and doc["first_unstable"] is None and all(doc["stable"])
    for i, n in enumerate(doc["platforms"]):
        am = ap.AssemblerModel.from_config({"platforms": n})
        result = ap.stiffness(am, am.home)
        C, C_el = result.compliance, elastic_compliance(am, am.home)
        assert doc["lateral"][i] == pytest.approx(1 / C[0, 0], rel=1e-12)
        assert doc["axial"][i] == pytest.approx(1 / C[2, 2], rel=1e-12)
        assert doc["torsional"][i] == pytest.approx(1 / C[5, 5], rel=1e-12)
        assert doc["sag"][i] == pytest.approx(np.linalg.norm(result.sag_translation), rel=1e-12)
        assert doc["elastic"]["lateral"][i] == pytest.approx(1 / C_el[0, 0], rel=1e-12)
    # one platform's springs alone: the closed form (Jᵀ k J)⁻¹ of the kinematics' EE Jacobian
    am = ap.AssemblerModel.from_config({"platforms": 1})
    J = ap.kinematics.ee_jacobian_wrt_lengths(am, am.home)
    assert doc["elastic"]["axial"][0] == pytest.approx(am.config.leg.stiffness / (J @ J.T)[2, 2], rel=1e-9)
    assert main(["stiffness", "--scaling", "--max-platforms", "2"]) == 0
    text = capsys.readouterr().out
    assert "lateral" in text and max(map(len, text.splitlines())) <= 100


def test_a_tall_stack_buckles_under_its_own_weight_and_its_springs_stay_defined():
    """Lateral stiffness falls like a cantilever's; the preload of the weight above softens it
    until, near 47 platforms at the defaults, the loaded equilibrium is no longer stable."""
    import dataclasses

    import assembler_pin as ap
    from assembler_pin.compliance.ee_stiffness import elastic_compliance
    from assembler_pin.compliance.scaling import _truss

    cfg = ap.load_config()
    standing, fallen = (_truss(dataclasses.replace(cfg, platforms=n)) for n in (46, 47))
    up, down = ap.stiffness(standing, standing.home), ap.stiffness(fallen, fallen.home)
    springs = 1 / elastic_compliance(standing, standing.home)[0, 0]
    assert up.success and 0 < up.weakest_stiffness < 0.1 * springs
    assert not down.success and "not stable" in down.message and np.all(np.isnan(down.stiffness))
    assert np.all(np.isfinite(elastic_compliance(fallen, fallen.home)))


@pytest.mark.parametrize(
    ("argv", "word"),
    [
        (["--scaling", "--max-platforms", "0"], "--max-platforms"),
        (["--scaling", "--max-platforms", "65"], "--max-platforms"),
        (["--scaling", "--out", "figure.jpg"], "--out"),
        (["--home", "--out", "figure.png"], "--out"),
    ],
)
def test_stiffness_scaling_refusals_are_one_line(capsys, argv, word):
    assert main(["stiffness", *argv]) == 2
    out, err = capsys.readouterr()
    assert not out and len(err.strip().splitlines()) == 1 and word in err
