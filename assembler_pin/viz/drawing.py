"""Shapes the viewer adds to Pinocchio's bodies: the helper arm, violation marks, the payload
rod, one-colour meshes and the ghost's wireframe payload. World frame O, metres."""

from __future__ import annotations

from pathlib import Path

import meshcat.geometry as mg
import numpy as np
import numpy.typing as npt
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer

from ..common.naming import names
from ..exceptions import AssemblerError
from ..model.assembler import AssemblerModel
from ..model.geometry import DIMENSIONS
from ..state import StackState
from .camera import cylinder_between, translation
from .colors import ARM_CLUSTER_RGBA, ARM_LINK_RGBA, PAYLOAD_RGBA, PAYLOAD_ROD_RGBA, VIOLATION_RGBA, material
from .placements import is_payload

__all__ = [
    "draw_helper_arm",
    "draw_payload_rod",
    "draw_violations",
    "paint_meshes",
    "violating_legs",
    "wireframe_payload",
]


def checked_points(points: npt.ArrayLike) -> np.ndarray:
    """``(m >= 2, 3)`` finite world points [m], else an :class:`AssemblerError`."""
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2 or not np.all(np.isfinite(pts)):
        raise AssemblerError(f"helper arm points must be a finite (m >= 2, 3) array, got shape {pts.shape}")
    return pts


def draw_helper_arm(root, pts: np.ndarray) -> None:
    """Violet links between consecutive points, dark violet joint clusters, under ``root``."""
    root.delete()
    link_r = 0.6 * DIMENSIONS.motor_radius
    for k in range(pts.shape[0] - 1):
        length = float(np.linalg.norm(pts[k + 1] - pts[k]))
        if length < 1e-9:
            continue
        node = root[f"link{k}"]
        node.set_object(mg.Cylinder(length, link_r), material(ARM_LINK_RGBA))
        node.set_transform(cylinder_between(pts[k], pts[k + 1]))
    for k in range(1, pts.shape[0] - 1):
        node = root[f"cluster{k}"]
        node.set_object(mg.Sphere(2.0 * DIMENSIONS.node_sphere_radius), material(ARM_CLUSTER_RGBA))
        node.set_transform(translation(pts[k]))
    for k in (0, pts.shape[0] - 1):
        node = root[f"end{k}"]
        node.set_object(mg.Sphere(1.2 * link_r), material(ARM_LINK_RGBA))
        node.set_transform(translation(pts[k]))


def violating_legs(state: StackState) -> list[tuple[int, int]]:
    """(platform, leg) of every leg with at least one violation, sorted."""
    return sorted({(v.platform, v.leg) for v in state.violations if v.platform is not None and v.leg is not None})


def draw_violations(root, state: StackState | None) -> None:
    """A yellow ball at the middle of every violating leg of ``state``, at ``root/<leg name>``
    (none for None)."""
    root.delete()
    if state is None:
        return
    for j, i in violating_legs(state):
        mid = 0.5 * (state.legs.bottom_points[j, i] + state.legs.top_points[j, i])
        node = root[names.leg(j, i)]
        node.set_object(mg.Sphere(2.2 * DIMENSIONS.motor_radius), material(VIOLATION_RGBA))
        node.set_transform(translation(mid))


def draw_payload_rod(node, am: AssemblerModel, R_ee: np.ndarray, p_ee: np.ndarray) -> bool:
    """A thin rod from the EE plate's centre to the payload, so it does not float; deleted
    (and False returned) when there is no offset payload."""
    offset = am.config.payload.offset
    if offset <= 0 or am.config.payload.mass <= 0:
        node.delete()
        return False
    b = R_ee @ np.array([0.0, 0.0, offset]) + p_ee
    node.set_object(mg.Cylinder(offset, 0.4 * DIMENSIONS.motor_radius), material(PAYLOAD_ROD_RGBA))
    node.set_transform(cylinder_between(p_ee, b))
    return True


def payload_rod_transform(am: AssemblerModel, R_ee: np.ndarray, p_ee: np.ndarray) -> np.ndarray:
    """Where :func:`draw_payload_rod` puts the rod for the EE plate pose (R_ee, p_ee)."""
    return cylinder_between(p_ee, R_ee @ np.array([0.0, 0.0, am.config.payload.offset]) + p_ee)


def paint_meshes(viz: MeshcatVisualizer, rgba: npt.ArrayLike) -> None:
    """Redraw every mesh-file visual of ``viz`` in one colour (a mesh file's own materials,
    e.g. a carrier's Collada colours, would otherwise be drawn; unscaled meshes only)."""
    loaders = {".dae": mg.DaeMeshGeometry, ".stl": mg.StlMeshGeometry, ".obj": mg.ObjMeshGeometry}
    for g in viz.visual_model.geometryObjects:
        loader = loaders.get(Path(str(g.meshPath)).suffix.lower())
        if loader is None or not np.allclose(g.meshScale, 1.0):
            continue
        node = viz.viewer[viz.getViewerNodeName(g, pin.GeometryType.VISUAL)]
        node.set_object(loader.from_file(g.meshPath), material(rgba))


def wireframe_payload(viz: MeshcatVisualizer, am: AssemblerModel) -> None:
    """Redraw the payload cube of ``viz`` as an opaque orange wireframe (placements are kept:
    meshcat keeps a node's transform when its object is replaced)."""
    for g in viz.visual_model.geometryObjects:
        if not is_payload(am, g):
            continue
        mat = material(PAYLOAD_RGBA)
        mat.wireframe = True
        viz.viewer[viz.getViewerNodeName(g, pin.GeometryType.VISUAL)].set_object(viz.loadPrimitive(g), mat)
