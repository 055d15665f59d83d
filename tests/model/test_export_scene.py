"""The exported URDF as other tools see it: yourdfpy + trimesh, exported to GLB.

yourdfpy is an independent URDF parser and forward kinematics; its scene must put every
body where Pinocchio puts it. Its FK ignores ``floating`` joints, so their origins are
set to the plate poses relative to the plate below (what a user of plain URDF tools
does); the leg joints go through ``update_cfg``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import trimesh
import yourdfpy

from assembler_pin import stack_forward_kinematics
from assembler_pin.common.naming import names
from assembler_pin.export import export_model_files
from assembler_pin.kinematics import q_from_plates


@pytest.fixture(scope="module")
def pose(am):
    lengths = np.full((am.n, 6), 0.275)
    lengths[0, :3] = 0.23
    lengths[1, 3:] = 0.33
    lengths[3] = np.linspace(0.22, 0.33, 6)
    fk = stack_forward_kinematics(am, lengths)
    assert fk.success
    return fk.plates


def posed_urdf(am, urdf_path, plates) -> yourdfpy.URDF:
    """Load with yourdfpy, put the floating joints at the relative plate poses, set the legs."""
    robot = yourdfpy.URDF.load(str(urdf_path), build_scene_graph=False, load_meshes=False).robot
    joints = {j.name: j for j in robot.joints}
    for j in range(am.n):
        joints[names.plate_joint(j)].origin = plates.se3(j).actInv(plates.se3(j + 1)).homogeneous
    urdf = yourdfpy.URDF(robot=robot, build_scene_graph=True, load_meshes=True)
    q = q_from_plates(am, plates)
    cfg = {}
    for j in range(am.n):
        for i in range(6):
            for part, k in (("ux", 0), ("uy", 1), ("actuator", 2)):
                cfg[names.leg(j, i, part)] = float(q[am.leg_idx_q[j, i, k]])
    urdf.update_cfg(cfg)
    return urdf


def expected_scene(am, plates) -> trimesh.Scene:
    """The same bodies built from Pinocchio's own geometry model and kinematics."""
    gmodel = pin.buildGeomFromUrdfString(am.model, am.urdf_text, pin.GeometryType.VISUAL)
    gdata = gmodel.createData()
    data = am.model.createData()
    pin.forwardKinematics(am.model, data, q_from_plates(am, plates))
    pin.updateGeometryPlacements(am.model, data, gmodel, gdata)
    scene = trimesh.Scene()
    for gid, g in enumerate(gmodel.geometryObjects):
        shape = g.geometry
        kind = type(shape).__name__
        if kind == "Cylinder":
            mesh = trimesh.creation.cylinder(radius=shape.radius, height=2 * shape.halfLength, sections=128)
        elif kind == "Sphere":
            mesh = trimesh.creation.icosphere(subdivisions=4, radius=shape.radius)
        elif kind == "Box":
            mesh = trimesh.creation.box(extents=2 * shape.halfSide)
        else:  # pragma: no cover - the generated URDF has primitives only
            raise AssertionError(f"unexpected shape {kind}")
        scene.add_geometry(mesh, transform=gdata.oMg[gid].homogeneous, geom_name=g.name)
    return scene


def test_yourdfpy_scene_matches_the_stack(am, pose, tmp_path):
    paths = export_model_files(am.config, tmp_path)
    urdf = posed_urdf(am, paths["urdf"], pose)

    # plates where the stack puts them, and every leg closing on its ball joint
    for k in range(am.n + 1):
        assert np.allclose(urdf.get_transform(names.plate(k)), pose.se3(k).homogeneous, atol=1e-9)
    bottom = np.matmul(am.geometry.bottom_in_plate, pose.R[:-1].transpose(0, 2, 1)) + pose.p[:-1, None, :]
    top = np.matmul(am.geometry.top_in_plate, pose.R[1:].transpose(0, 2, 1)) + pose.p[1:, None, :]
    for j in range(am.n):
        for i in range(6):
            assert np.allclose(urdf.get_transform(names.leg(j, i, "motor"))[:3, 3], bottom[j, i], atol=1e-9)
            assert np.allclose(urdf.get_transform(names.leg(j, i, "shaft"))[:3, 3], top[j, i], atol=1e-9)
            assert np.allclose(urdf.get_transform(names.leg(j, i, "top"))[:3, 3], top[j, i], atol=1e-9)

    # export to GLB and read it back: one mesh per <visual>, grouped by link
    glb = urdf.scene.export(file_type="glb")
    out = tmp_path / "assembler.glb"
    out.write_bytes(glb)
    scene = trimesh.load(str(out), file_type="glb")
    shaped_payload = int(am.config.payload.radius > 0)  # a point-mass payload has no shape
    n_visual_links = (am.n + 1) + 2 * 6 * am.n + shaped_payload  # plates, motors + shafts, payload
    n_visuals = 4 * (am.n + 1) + 2 * 6 * am.n + shaped_payload  # each plate: disc + 3 node spheres
    assert len(urdf.scene.graph.nodes_geometry) == n_visuals
    assert len(scene.graph.nodes_geometry) == n_visuals
    parents = urdf.scene.graph.transforms.parents
    links = {parents[g] for g in urdf.scene.graph.nodes_geometry}
    assert len(links) == n_visual_links
    assert {names.plate(k) for k in range(am.n + 1)} | ({names.payload} if shaped_payload else set()) <= links

    # the exported extent is the stack's extent computed from Pinocchio's geometry
    ref = expected_scene(am, pose)
    assert np.allclose(scene.bounds, ref.bounds, atol=2e-3), (scene.bounds, ref.bounds)
    # and the extent covers the stack from below the base disc to the EE plate (and the
    # payload's sphere when it has one)
    top = am.config.payload.offset + am.config.payload.radius if shaped_payload else 0.0
    assert scene.bounds[1, 2] >= (pose.R[-1] @ [0, 0, top] + pose.p[-1])[2]
    assert scene.bounds[0, 2] < 0.0 < scene.bounds[1, 2]
