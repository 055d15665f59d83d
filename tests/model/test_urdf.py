"""URDF + sidecar export: repository files up to date, both parsers load them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
import yourdfpy

from assembler_pin import AssemblerModel, load_config
from assembler_pin.cli import main
from assembler_pin.export import export_model_files
from assembler_pin.kinematics import q_from_plates

REPO_URDF = Path(__file__).resolve().parents[2] / "urdf"


def test_repository_urdf_matches_export(tmp_path):
    assert main(["export", "--mjcf", "--out", str(tmp_path)]) == 0
    for name in ("assembler.urdf", "assembler.yaml", "helper_arm.urdf", "assembler.xml"):
        assert (REPO_URDF / name).read_text() == (tmp_path / name).read_text(), (
            f"urdf/{name} is stale: run 'assembler-pin export --mjcf --out urdf'"
        )


@pytest.mark.parametrize("platforms", [1, 2, 4, 7])
def test_any_number_of_platforms_loads_in_pinocchio(tmp_path, platforms):
    cfg = load_config({"platforms": platforms})
    paths = export_model_files(cfg, tmp_path)
    model = pin.buildModelFromUrdf(str(paths["urdf"]))
    assert model.nv == 24 * platforms  # fixed base: 6 free-flyer + 6 x 3 leg joints per SP
    am = AssemblerModel.from_files(paths["urdf"])
    assert am.nv == 6 + 24 * platforms
    assert len(am.constraint_models) == 6 * platforms
    total = (platforms + 1) * cfg.plate.mass + 6 * platforms * (cfg.leg.motor_mass + cfg.leg.shaft_mass)
    assert am.total_mass() == pytest.approx(total + cfg.payload.mass, rel=1e-12)


def test_sidecar_convention():
    side = yaml.safe_load((REPO_URDF / "assembler.yaml").read_text())
    assert set(side) == {"closed_loop", "type", "name_mot", "assembler_config"}
    assert len(side["closed_loop"]) == 24 and side["type"] == ["3d"] * 24
    assert side["closed_loop"][0] == ["sp0_leg0_shaft", "sp0_leg0_top"]
    assert side["name_mot"][5] == "sp0_leg5_actuator"
    assert load_config(side["assembler_config"]) == load_config()


def test_every_link_has_inertial_and_leg_chains_are_rx_ry_prismatic():
    robot = yourdfpy.URDF.load(
        str(REPO_URDF / "assembler.urdf"), load_meshes=False, build_collision_scene_graph=False
    ).robot
    assert all(link.inertial is not None for link in robot.links)
    joints = {j.name: j for j in robot.joints}
    assert joints["sp2_leg3_ux"].type == "revolute" and np.allclose(joints["sp2_leg3_ux"].axis, [1, 0, 0])
    assert joints["sp2_leg3_uy"].type == "revolute" and np.allclose(joints["sp2_leg3_uy"].axis, [0, 1, 0])
    assert joints["sp2_leg3_actuator"].type == "prismatic"
    assert joints["sp2_leg3_actuator"].limit.lower == 0.2 and joints["sp2_leg3_actuator"].limit.upper == 0.35
    assert sum(j.type == "floating" for j in robot.joints) == 4


def test_yourdfpy_closes_the_loops_for_our_configuration(am, random_poses):
    """Second parser: with yourdfpy's own FK, every shaft tip meets its top anchor."""
    urdf = yourdfpy.URDF.load(str(REPO_URDF / "assembler.urdf"), load_meshes=False, build_collision_scene_graph=False)
    _, plates = random_poses[0]
    q = q_from_plates(am, plates)
    cfg = {}
    for j in range(am.n):
        for i in range(6):
            for part, k in (("ux", 0), ("uy", 1), ("actuator", 2)):
                cfg[f"sp{j}_leg{i}_{part}"] = q[am.leg_idx_q[j, i, k]]
        # yourdfpy ignores floating joints in FK: set their origin instead
        rel = plates.se3(j).actInv(plates.se3(j + 1))
        urdf.robot.joints[[jt.name for jt in urdf.robot.joints].index(f"sp{j}_plate")].origin = rel.homogeneous
    urdf._scene = None
    urdf = yourdfpy.URDF(robot=urdf.robot, load_meshes=False, build_collision_scene_graph=False)
    urdf.update_cfg(cfg)
    worst = 0.0
    for j in range(am.n):
        assert np.allclose(
            urdf.get_transform(f"plate_{j + 1}", "plate_0"),
            (plates.se3(0).actInv(plates.se3(j + 1))).homogeneous,
            atol=1e-12,
        )
        for i in range(6):
            tip = urdf.get_transform(f"sp{j}_leg{i}_shaft", "plate_0")[:3, 3]
            anchor = urdf.get_transform(f"sp{j}_leg{i}_top", "plate_0")[:3, 3]
            worst = max(worst, np.linalg.norm(tip - anchor))
    assert worst < 1e-12
