"""Where every visual of the stack goes: Pinocchio's kinematics or the closed form.

Up to :data:`~assembler_pin.model.WHOLE_DATA_MAX_PLATFORMS` the bodies are placed by
Pinocchio's kinematics of the whole stack; above, its ``Data`` (cubic in n) is never made and
every visual is placed in closed form from the plate poses and the legs' joint centres.
World frame O, metres; 4×4 homogeneous transforms.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer

from ..common.naming import names, parse_name
from ..kinematics import PlateArrays, leg_state, plate_arrays, q_from_plates
from ..model.assembler import AssemblerModel
from ..model.geometry import DIMENSIONS
from ..state import StackState
from .camera import frame_along_axis

__all__ = [
    "CallerPlacedVisualizer",
    "GeometryFrame",
    "as_plates",
    "closed_form_placements",
    "drawn_joint_centres",
    "geometry_frames",
    "leg_geometries",
    "make_visualizer",
    "pinocchio_placements",
    "stack_points",
    "stack_visuals",
]

GeometryFrame = tuple[str, tuple[int, ...], np.ndarray]
"""A visual's body kind (``plate``, ``motor``, ``shaft``, ``payload``), its indices (as
:func:`~assembler_pin.common.naming.parse_name`) and its 4×4 placement in its joint's frame."""

Pose = StackState | PlateArrays | Sequence | np.ndarray


def as_plates(am: AssemblerModel, pose: Pose) -> PlateArrays:
    """The world plate poses of a state or of plate poses in any accepted form."""
    return pose.plates if isinstance(pose, StackState) else plate_arrays(am, pose)


class CallerPlacedVisualizer(MeshcatVisualizer):
    """A ``MeshcatVisualizer`` whose bodies the caller places (:func:`closed_form_placements`):
    it never runs kinematics on its ``Data``, which is left empty for large stacks."""

    def updatePlacements(self, geometry_type) -> None:  # noqa: N802 - Pinocchio's name
        return None


def make_visualizer(
    am: AssemblerModel,
    visual_model: pin.GeometryModel,
    vis,
    root: str,
    rgba: npt.ArrayLike | None = None,
    closed_form: bool = False,
) -> MeshcatVisualizer:
    """A visualizer of the stack's bodies under the meshcat path ``root`` of ``vis`` (in one
    colour ``rgba`` if given); with ``closed_form`` its ``Data`` stays empty and the caller
    places its bodies (:func:`closed_form_placements`)."""
    if closed_form:
        viz = CallerPlacedVisualizer(am.model, None, visual_model, copy_models=False, data=pin.Data())
    else:
        viz = MeshcatVisualizer(am.model, None, visual_model, copy_models=False)
    viz.initViewer(viewer=vis)
    viz.loadViewerModel(rootNodeName=root, visual_color=None if rgba is None else [float(c) for c in np.asarray(rgba)])
    return viz


def stack_visuals(am: AssemblerModel) -> pin.GeometryModel:
    """The visuals the viewer draws: the model's URDF visuals, without the payload cube when
    the payload has no mass (a stack that carries no tool is drawn without one)."""
    visual_model = pin.buildGeomFromUrdfString(am.model, am.urdf_text, pin.GeometryType.VISUAL)
    if am.config.payload.mass <= 0:
        for g in [g for g in visual_model.geometryObjects if is_payload(am, g)]:
            visual_model.removeGeometryObject(g.name)
    return visual_model


def leg_geometries(am: AssemblerModel, visual_model: pin.GeometryModel) -> dict[tuple[int, int], list[int]]:
    """Geometry ids of the motor and shaft of every leg, keyed by (platform, leg)."""
    frames = am.model.frames
    out: dict[tuple[int, int], list[int]] = {}
    for gid, g in enumerate(visual_model.geometryObjects):
        body = parse_name(frames[g.parentFrame].name)
        if body.kind in ("motor", "shaft"):
            j, i = body.indices
            out.setdefault((j, i), []).append(gid)
    return out


def geometry_frames(am: AssemblerModel, visual_model: pin.GeometryModel) -> list[GeometryFrame]:
    """For each visual: its body and its placement in the frame of the joint that moves it,
    as Pinocchio stores it: the plate's, the universal joint's (motor) or the actuator's (shaft)."""
    frames = am.model.frames
    out: list[GeometryFrame] = []
    for g in visual_model.geometryObjects:
        body = parse_name(frames[g.parentFrame].name)
        out.append((body.kind, body.indices, g.placement.homogeneous))
    return out


def pinocchio_placements(viz: MeshcatVisualizer, am: AssemblerModel, plates: PlateArrays) -> list[np.ndarray]:
    """World placement (4×4) of every visual of ``viz`` from Pinocchio's whole-stack kinematics."""
    model, data, vdata = viz.model, viz.data, viz.visual_data
    pin.forwardKinematics(model, data, q_from_plates(am, plates))
    pin.updateGeometryPlacements(model, data, viz.visual_model, vdata)
    return [vdata.oMg[k].homogeneous for k in range(len(viz.visual_model.geometryObjects))]


def closed_form_placements(am: AssemblerModel, frames: list[GeometryFrame], pose: Pose) -> list[np.ndarray]:
    """World placement (4×4) of every visual in closed form: plates and payload from the plate
    poses, each leg's motor frame at its universal-joint centre and its shaft frame at its
    ball-joint centre, both with z along the leg (motor and shaft are cylinders about that
    axis, so the turn about it does not show)."""
    plates = as_plates(am, pose)
    legs = pose.legs if isinstance(pose, StackState) else leg_state(am, plates)
    bottom, top = legs.bottom_points, legs.top_points
    T_plates = plates.as_matrices()
    out = []
    for body, idx, local in frames:
        if body == "plate":
            frame = T_plates[idx[0]]
        elif body == "payload":  # fixed to the EE plate: its placement is in the plate's joint frame
            frame = T_plates[-1]
        else:
            frame = frame_along_axis(top[idx] - bottom[idx], bottom[idx] if body == "motor" else top[idx])
        out.append(frame @ local)
    return out


def drawn_joint_centres(viz: MeshcatVisualizer, am: AssemblerModel) -> tuple[np.ndarray, np.ndarray]:
    """(n, 6, 3) world universal- and ball-joint centres [m] as ``viz``'s kinematics placed
    them (motor frame origin = universal-joint centre, shaft frame origin = ball-joint centre)."""
    model, data = viz.model, viz.data
    pin.updateFramePlacements(model, data)
    legs = [(j, i) for j in range(am.n) for i in range(6)]

    def centres(part: str) -> np.ndarray:
        points = [data.oMf[model.getFrameId(names.leg(j, i, part))].translation for j, i in legs]
        return np.array(points).reshape(am.n, 6, 3)

    return centres("motor"), centres("shaft")


def stack_points(am: AssemblerModel, pose: Pose) -> np.ndarray:
    """World points bounding a drawn stack [m]: plate rims, the payload sphere's top (when it
    has a mass and a radius, as :func:`stack_visuals` draws it)."""
    plates = as_plates(am, pose)
    r = am.config.plate.node_radius + DIMENSIONS.node_sphere_radius
    ang = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    rim = np.stack([r * np.cos(ang), r * np.sin(ang), np.zeros_like(ang)], axis=1)
    pts = [np.einsum("kab,mb->kma", plates.R, rim).reshape(-1, 3) + np.repeat(plates.p, len(ang), axis=0)]
    top = am.config.payload.offset + am.config.payload.radius
    payload = plates.R[-1] @ np.array([0.0, 0.0, top]) + plates.p[-1]
    if am.config.payload.mass > 0 and am.config.payload.radius > 0:
        pts.append(payload[None, :])
    return np.concatenate(pts)


def is_payload(am: AssemblerModel, geometry: pin.GeometryObject) -> bool:
    """Whether a visual belongs to the payload body."""
    return am.model.frames[geometry.parentFrame].name == names.payload
