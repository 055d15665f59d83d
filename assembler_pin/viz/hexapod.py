"""The hexapod's page: every stack drawn by its own visualizer in one meshcat scene, each leg
coloured by its force, the body as a disc on the EE plates, the support polygon of the feet on
the floor and the machine's centre of mass (over its floor projection), in a standalone page
(:func:`write_hexapod_page`). World frame, metres.

Meshcat paths: ``hexapod/stack{i}`` (the stacks), ``hexapod/body``, ``hexapod/support``
(the polygon's edges), ``hexapod/com`` and ``hexapod/com_floor``.
"""

from __future__ import annotations

import logging
from pathlib import Path

import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
from scipy.spatial import ConvexHull, QhullError

from ..common.files import write_atomic
from ..hexapod import HexapodStand
from ..kinematics import PlateArrays, q_from_plates
from ..model.assembler import AssemblerModel
from . import placements as pl
from .camera import camera_for_points, cylinder_between, frame_along_axis, point_camera, translation
from .colors import FLOOR_RGBA, PAYLOAD_RGBA, VIOLATION_RGBA, force_color, material
from .overlay import force_items, overlay_html
from .server import DEFAULT_HOST, connect

__all__ = ["HexapodScene", "write_hexapod_page"]

logger = logging.getLogger(__name__)


class HexapodScene:
    """The drawn hexapod (module doc) in a meshcat server this object starts and stops.

    Attributes:
        visualizers: each stack's :class:`pinocchio.visualize.MeshcatVisualizer`.
        force_range: (tension, compression) [N] where the leg colours saturate: the legs'
            force limits.
    """

    def __init__(self, am: AssemblerModel, result: HexapodStand, host: str = DEFAULT_HOST) -> None:
        self.am, self.result = am, result
        self.server, self.meshcat = connect(host)
        leg = am.config.leg
        self.force_range = (leg.max_tension, leg.max_compression)
        visual_model = pin.buildGeomFromUrdfString(am.model, am.urdf_text, pin.GeometryType.VISUAL)
        legs = pl.leg_geometries(am, visual_model)
        self.visualizers = []
        self._roots: list[str] = []
        points = []
        for i in range(result.plates.shape[0]):
            root = f"hexapod/stack{i}"
            viz = pl.make_visualizer(am, visual_model, self.meshcat, root)
            colors = force_color(result.forces[i], *self.force_range)
            for (j, k), gids in legs.items():
                for gid in gids:
                    viz.loadViewerGeometryObject(
                        visual_model.geometryObjects[gid], pin.GeometryType.VISUAL, [*colors[j, k], 1.0]
                    )
            plates = PlateArrays(result.plates[i, :, :3, :3], result.plates[i, :, :3, 3])
            viz.display(q_from_plates(am, plates))
            self.visualizers.append(viz)
            self._roots.append(root)
            points.append(pl.stack_points(am, plates))
        self._points = np.concatenate([*points, self._draw_machine()])

    def _draw_machine(self) -> np.ndarray:
        """The body, the support polygon and the centre of mass; returns points to frame."""
        am, result, vis = self.am, self.result, self.meshcat
        hc, plate = am.config.hexapod, am.config.plate
        turn = pin.exp3(result.body_displacement[3:])
        centre = result.plates[:, -1, :3, 3].mean(axis=0) + turn[:, 2] * 0.5 * (plate.thickness + hc.body_thickness)
        body = vis["hexapod/body"]
        body.set_object(mg.Cylinder(max(hc.body_thickness, 1e-3), hc.body_radius), material(PAYLOAD_RGBA))
        body.set_transform(frame_along_axis(turn[:, 2], centre, column=1))
        feet = result.plates[~result.lifted, 0, :3, 3] - [0.0, 0.0, 0.5 * plate.thickness]
        try:
            hull = feet[ConvexHull(feet[:, :2]).vertices] if len(feet) >= 3 else feet
        except QhullError:
            hull = feet
        support = vis["hexapod/support"]
        support.delete()
        for e, (a, b) in enumerate(zip(hull, np.roll(hull, -1, axis=0), strict=True)):
            if np.linalg.norm(b - a) > 1e-9:
                support[f"edge{e}"].set_object(mg.Cylinder(float(np.linalg.norm(b - a)), 0.004), material(FLOOR_RGBA))
                support[f"edge{e}"].set_transform(cylinder_between(a, b))
        floor = np.array([*result.com[:2], feet[:, 2].min() if len(feet) else 0.0])
        vis["hexapod/com"].set_object(mg.Sphere(0.02), material(VIOLATION_RGBA))
        vis["hexapod/com"].set_transform(translation(result.com))
        vis["hexapod/com_floor"].set_object(
            mg.Cylinder(float(result.com[2] - floor[2]), 0.003), material(VIOLATION_RGBA)
        )
        vis["hexapod/com_floor"].set_transform(cylinder_between(floor, result.com))
        self._roots += ["hexapod/body", "hexapod/support", "hexapod/com", "hexapod/com_floor"]
        rim = np.array([hc.body_radius, 0.0, 0.0])
        return np.vstack([centre + rim, centre - rim, floor])

    def static_html(self, path: str | Path) -> str:
        """Frame the machine from the side and write the standalone page to ``path`` (atomically)."""
        point_camera(self.meshcat, camera_for_points(self._points), self._roots)
        result = self.result
        margin = result.stability_margin_m
        title = f"hexapod of {result.forces.shape[0]} stacks, feet {result.feet}, max|F| {result.max_abs_force:.1f} N"
        items = [
            *force_items(),
            (PAYLOAD_RGBA, f"body {result.body_mass:g} kg"),
            (VIOLATION_RGBA, "centre of mass over its floor projection"),
            (FLOOR_RGBA, "support polygon" + ("" if np.isnan(margin) else f": margin {1e3 * margin:.0f} mm")),
        ]
        html = self.meshcat.static_html().replace(
            "</body>", overlay_html(title, items, self.force_range) + "\n</body>", 1
        )
        write_atomic(path, html)
        logger.info("wrote %s (%d bytes)", path, len(html))
        return html

    def close(self) -> None:
        """Stop the meshcat server."""
        self.server.stop()


def write_hexapod_page(am: AssemblerModel, result: HexapodStand, path: str | Path) -> Path:
    """Draw ``result`` (module doc) and write its standalone page to ``path``."""
    scene = HexapodScene(am, result)
    try:
        scene.static_html(path)
    finally:
        scene.close()
    return Path(path)
