"""The stack and its page in Meshcat: :class:`StackScene` owns the server, the main stack's
bodies (legs colored by force, violation marks, payload rod), animations, the overlay, the
camera and the standalone page. :class:`~assembler_pin.viz.viewer.StackViewer` adds what is
drawn beside the stack.

Bodies are Pinocchio's :class:`~pinocchio.visualize.MeshcatVisualizer` of a visual model parsed
from the generated URDF (primitive shapes only), placed by :mod:`.placements`. World frame O
(z up), SI units. The scene is translated by :attr:`StackScene.scene_offset` for framing
(:mod:`.camera`); poses passed to the API are always world poses.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Sequence
from pathlib import Path
from typing import TypeVar

import meshcat
import meshcat.animation
import numpy as np
import numpy.typing as npt
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer

from ..collision.check import clearance
from ..collision.scene import Scene, read_scene
from ..common.files import write_atomic
from ..config.choices import FORCE_SCALES
from ..exceptions import AssemblerError, ViewerError
from ..kinematics import PlateArrays, q_from_plates
from ..model.assembler import WHOLE_DATA_MAX_PLATFORMS, AssemblerModel
from ..state import StackState, evaluate_state
from . import animation as anim_mod
from . import drawing, obstacles, overlay
from . import placements as pl
from .camera import DEFAULT_ELEVATION_DEG, Camera, camera_for_points, point_camera
from .colors import (
    CLOSEST_PAIR_RGBA,
    FLOOR_RGBA,
    OBSTACLE_RGBA,
    PAYLOAD_RGBA,
    VIOLATION_RGBA,
    color_scale,
    force_color,
)
from .server import DEFAULT_HOST, ServerProcess, connect

__all__ = ["Pose", "StackScene"]

logger = logging.getLogger(__name__)

Pose = StackState | PlateArrays | Sequence | np.ndarray


_Scene = TypeVar("_Scene", bound="StackScene")


class StackScene:
    """Meshcat scene of an Assembler: the main stack, its animations and its page.

    Args:
        am: the model to draw.
        viewer: an existing ``meshcat.Visualizer`` to draw into; default: start a meshcat
            server owned by this object (:func:`~assembler_pin.viz.server.start_server`),
            stopped by :meth:`close`, or with this process however it ends.
        prefix: meshcat path of the main stack.
        open: open the viewer's URL in a web browser.
        host: interface the started server's page listens on (``127.0.0.1``, the default:
            this machine only; ``0.0.0.0``: every interface).
        port: web port of the started server (default: the first free one from 7000).
        force_scale: default color scale of the legs (:data:`FORCE_SCALES`).
        scene: obstacles and a floor (a :class:`~assembler_pin.collision.scene.Scene` or a
            scene file), drawn with the first pose shown; every pose shown then has its
            clearance taken with them and its closest pair marked
            (:mod:`~assembler_pin.viz.obstacles`).

    Attributes:
        viz: the :class:`pinocchio.visualize.MeshcatVisualizer` of the main stack.
        server: the meshcat server subprocess this viewer started (None when borrowed).
        meshcat: the underlying ``meshcat.Visualizer``.
        scene_offset: translation applied to the whole scene for framing [m].
        scene: the obstacles and floor drawn, or None.
        closest: the closest pair marked on the pose shown, or None.
    """

    def __init__(
        self,
        am: AssemblerModel,
        viewer: meshcat.Visualizer | None = None,
        prefix: str = "assembler",
        open: bool = False,
        host: str = DEFAULT_HOST,
        port: int | None = None,
        force_scale: str = "auto",
        scene: Scene | str | None = None,
    ) -> None:
        self.scene: Scene | None = read_scene(scene)  # refused before a server starts
        self.closest: obstacles.ClosestPair | None = None
        self._scene_drawn = False
        if force_scale not in FORCE_SCALES:
            raise ViewerError(f"force_scale must be one of {', '.join(FORCE_SCALES)}, got {force_scale!r}")
        self.force_scale, self.am, self.prefix = force_scale, am, prefix
        self.whole_stack_kinematics = am.n <= WHOLE_DATA_MAX_PLATFORMS  # else closed-form placements
        self.server: ServerProcess | None = None
        if viewer is None:
            self.server, viewer = connect(host, port)
        self.meshcat: meshcat.Visualizer = viewer
        self.visual_model = pl.stack_visuals(am)
        self._geometry_frames = pl.geometry_frames(am, self.visual_model)
        self.scene_offset = np.zeros(3)
        self._ghosts: dict[str, MeshcatVisualizer] = {}  # second visualizers, by name
        self._legend: dict[str, overlay.LegendItem] = {}  # what is drawn besides the legs, by path
        self._extra_points: dict[str, np.ndarray] = {}
        self._roots: list[str] = [prefix, self.scene_path("violations")]
        self.state: StackState | None = None
        self.title = ""
        self.force_range = (am.config.leg.max_tension, am.config.leg.max_compression)
        self.forces_shown = True  # the legs carry force colours: legend and colour bar say so
        self._animated = False
        self.viz = self._make_visualizer(prefix)
        self._leg_geoms = pl.leg_geometries(am, self.visual_model)
        if open:
            self.meshcat.open()
        logger.info("meshcat viewer at %s", self.url)

    # ------------------------------------------------------------------ plumbing
    def scene_path(self, what: str) -> str:
        """The meshcat root of one kind of drawing beside the main stack: ``{prefix}_{what}``."""
        return f"{self.prefix}_{what}"

    def _add_root(self, root: str, points: np.ndarray | None = None) -> None:
        if root not in self._roots:
            self._roots.append(root)
        if points is not None:
            self._extra_points[root] = points

    def _make_visualizer(self, root: str, rgba: npt.ArrayLike | None = None) -> MeshcatVisualizer:
        closed_form = not self.whole_stack_kinematics
        return pl.make_visualizer(self.am, self.visual_model, self.meshcat, root, rgba, closed_form)

    def placements(self, pose: StackState | PlateArrays) -> list[np.ndarray]:
        """World placement (4×4) of every visual for a pose, in ``visual_model`` order
        (Pinocchio's kinematics of the whole stack, or the closed form above
        ``WHOLE_DATA_MAX_PLATFORMS``: :mod:`~assembler_pin.viz.placements`)."""
        if self.whole_stack_kinematics:
            return pl.pinocchio_placements(self.viz, self.am, pl.as_plates(self.am, pose))
        return pl.closed_form_placements(self.am, self._geometry_frames, pose)

    def _place(self, viz: MeshcatVisualizer, pose: StackState | PlateArrays) -> None:
        """Put every body of ``viz`` at ``pose``."""
        if self.whole_stack_kinematics:
            viz.display(q_from_plates(self.am, pl.as_plates(self.am, pose)))
            return
        for g, T in zip(self.visual_model.geometryObjects, self.placements(pose), strict=True):
            self.meshcat[viz.getViewerNodeName(g, pin.GeometryType.VISUAL)].set_transform(T)

    @property
    def url(self) -> str:
        """URL of the live viewer (served on ``host``, 127.0.0.1 by default)."""
        return self.meshcat.url()

    def close(self) -> None:
        """Stop the meshcat server this viewer started and wait for it to end (a borrowed
        viewer is left running). Safe to call twice."""
        if self.server is not None:
            with contextlib.suppress(Exception):
                self.meshcat.window.zmq_socket.close(linger=0)
            self.server.stop()

    def __enter__(self: _Scene) -> _Scene:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ the main stack
    def display(
        self, pose: Pose, color_forces: bool = True, mark_violations: bool = True, force_scale: str | None = None
    ) -> StackState:
        """Show a pose; color each leg by its force and mark violating legs; returns the state.

        A stored animation is removed first (it would replay over this pose).

        Args:
            pose: a :class:`StackState`, or world plate poses (their state is computed).
            color_forces: color motor and shaft by the actuator force (else URDF colors).
            mark_violations: a yellow ball at the middle of every leg that violates a limit,
                at ``{prefix}_violations/<leg name>`` (:func:`~assembler_pin.common.naming.names`).
            force_scale: where the colors saturate (:data:`FORCE_SCALES`; default the
                viewer's); the numbers are in :attr:`force_range` and on the color bar.
        """
        state = pose if isinstance(pose, StackState) else evaluate_state(self.am, pose, scene=self.scene)
        self.state = state
        self._clear_animation()
        self.force_range = self.color_scale(state, force_scale or self.force_scale)
        self.forces_shown = color_forces
        self._color_legs(state, color_forces)
        self._place(self.viz, state)
        drawing.draw_violations(self.meshcat[self.scene_path("violations")], state if mark_violations else None)
        rod = self.scene_path("payload_rod")
        if drawing.draw_payload_rod(self.meshcat[rod]["rod"], self.am, state.plates.R[-1], state.plates.p[-1]):
            self._add_root(rod)  # the rod's root carries the framing shift
        self._extra_points["stack"] = pl.stack_points(self.am, state)
        if self.scene is not None:
            self._draw_scene()
            self.show_closest_pair(state if mark_violations else None)
        return state

    def _draw_scene(self) -> None:
        """The scene's obstacles and floor at ``{prefix}_obstacles`` (once), named in the legend."""
        if self.scene is None or self._scene_drawn:
            return
        root = self.scene_path("obstacles")
        pts = obstacles.draw_scene(self.meshcat[root], self.scene, self._extra_points["stack"])
        self._add_root(root, pts if len(pts) else None)
        names = [o.name for o in self.scene.obstacles]
        shown = ", ".join(names[:8]) + (f" and {len(names) - 8} more" if len(names) > 8 else "")
        if names:
            self._legend[f"{root}/obstacles"] = (OBSTACLE_RGBA, f"obstacles: {shown}")
        if self.scene.floor_z is not None:
            self._legend[f"{root}/floor"] = (FLOOR_RGBA, f"floor at z = {self.scene.floor_z:g} m")
        self._scene_drawn = True

    def show_closest_pair(self, pose: Pose | None) -> obstacles.ClosestPair | None:
        """Mark the closest pair of bodies of ``pose`` (its clearance with :attr:`scene`): a
        cyan segment between the two witness points at ``{prefix}_closest``, its distance [m]
        and the two bodies in the legend. None removes the mark. Returns what is marked."""
        root = self.scene_path("closest")
        self._legend.pop(root, None)
        pair = None
        if pose is not None:
            plates = pl.as_plates(self.am, pose)
            pair = obstacles.closest_pair(clearance(self.am, plates, self.scene))
        obstacles.draw_closest_pair(self.meshcat[root], pair)
        self.closest = pair
        if pair is not None:
            self._add_root(root)
            self._legend[root] = (CLOSEST_PAIR_RGBA, pair.label)
        return pair

    def _color_legs(self, state: StackState, color_forces: bool) -> None:
        """Colour motor and shaft of every leg by its force on :attr:`force_range` (else the
        URDF's colours)."""
        colors = force_color(state.forces, *self.force_range)
        for (j, i), gids in self._leg_geoms.items():
            for gid in gids:
                g = self.visual_model.geometryObjects[gid]
                rgba = [*colors[j, i], 1.0] if color_forces else list(g.meshColor)
                self.viz.loadViewerGeometryObject(g, pin.GeometryType.VISUAL, rgba)

    def color_scale(self, state: StackState, force_scale: str = "auto") -> tuple[float, float]:
        """(tension, compression) [N] at which the leg colors saturate (see :data:`FORCE_SCALES`)."""
        return color_scale(state, self.am.config.leg, force_scale)

    violating_legs = staticmethod(drawing.violating_legs)

    def drawn_leg_endpoints(self) -> tuple[np.ndarray, np.ndarray]:
        """World joint centres of the legs as drawn: (n, 6, 3) bottom and top [m], read back
        from the visualizer's kinematics; in closed form, the joint centres it places."""
        if self.whole_stack_kinematics:
            return pl.drawn_joint_centres(self.viz, self.am)
        if self.state is None:
            raise AssemblerError("nothing drawn yet: call display() first")
        return self.state.legs.bottom_points.copy(), self.state.legs.top_points.copy()

    # ------------------------------------------------------------------ animation
    def animate(
        self,
        states: Sequence[StackState | PlateArrays],
        fps: float = 15.0,
        repetitions: int = 1,
        play: bool = True,
        color_forces: bool = False,
    ) -> None:
        """Store the sequence as a meshcat animation (plays in the live and static page).

        The stack is displayed at the first state and the page ends on the last; a later
        :meth:`display` removes the animation. Build ``states`` with
        :func:`~assembler_pin.viz.animation.interpolate_states` or
        :func:`~assembler_pin.motion.timing.trajectory_states`. ``fps``: frames per second;
        ``color_forces``: animate each leg's force color too (``states`` must be states): every
        frame recolours each leg (a sleeve joint to joint) on one scale, that of the whole
        sequence's forces (:func:`~assembler_pin.viz.animation.animation_scale`), which the
        colour bar shows.
        """
        if len(states) < 2:
            raise AssemblerError("an animation needs at least two states")
        if color_forces and not all(isinstance(st, StackState) for st in states):
            raise AssemblerError("color_forces needs StackState frames (their forces)")
        scale = None
        if color_forces:
            forces = [st.forces for st in states if isinstance(st, StackState)]
            scale = anim_mod.animation_scale(forces, self.am.config.leg, self.force_scale)
            anim_mod.make_force_bands(self.meshcat[self.scene_path("force_bands")], self.am, scale)
            self._add_root(self.scene_path("force_bands"))
        first = states[0]
        first_state = first if isinstance(first, StackState) else evaluate_state(self.am, first, scene=self.scene)
        self.display(first_state)
        if self.scene is not None:  # one pose's mark would stand still while the poses move
            self.show_closest_pair(None)
        if scale is not None:  # one scale for the whole animation: the legs, the sleeves, the bar
            self.force_range = scale
            self._color_legs(first_state, True)
        self.meshcat.set_animation(
            anim_mod.build_animation(self, states, fps, color_forces, scale), play=play, repetitions=repetitions
        )
        self._extra_points.update({f"anim{k}": pl.stack_points(self.am, st) for k, st in enumerate(states)})
        self._animated = True
        self._place(self.viz, first)

    def _clear_animation(self) -> None:
        """Replace a stored animation by an empty one (meshcat cannot delete one); sent before
        any new transform: stopping an animation restores the bodies to where they started."""
        if not self._animated:
            return
        self.meshcat.set_animation(meshcat.animation.Animation(), play=False)
        self.meshcat[self.scene_path("force_bands")].delete()
        self._animated = False
        for key in [k for k in self._extra_points if k.startswith("anim")]:
            del self._extra_points[key]

    # ------------------------------------------------------------------ page
    def set_title(self, title: str) -> None:
        """The title of the page's overlay (e.g. the scenario or goal and max|F|)."""
        self.title = str(title)
        self.push_overlay()

    def push_overlay(self) -> None:
        """Send the overlay to the live page (a borrowed server has none; a standalone page
        always embeds it, see :meth:`static_html`)."""
        if self.server is not None:
            overlay.send_overlay(self.meshcat, self.overlay_html())

    def overlay_html(self) -> str:
        """The page's overlay: title, legend of every color and marker drawn, color bar [N]."""
        items = (overlay.force_items() if self.forces_shown else []) + list(self._legend.values())
        if self.state is not None and self.violating_legs(self.state):
            items.append((VIOLATION_RGBA, "yellow ball: leg violating a limit"))
        if self.am.config.payload.mass > 0:
            items.append((PAYLOAD_RGBA, f"payload {self.am.config.payload.mass:g} kg"))
        return overlay.overlay_html(self.title, items, self.force_range if self.forces_shown else None)

    def frame(
        self, elevation_deg: float = DEFAULT_ELEVATION_DEG, azimuth_deg: float = -90.0, show_grid: bool = True
    ) -> Camera:
        """Point the camera at everything drawn, from the side (z up), framing it whole
        (the scene is translated by :attr:`scene_offset`: meshcat orbits the origin)."""
        if not self._extra_points:
            raise AssemblerError("nothing drawn yet: call display() first")
        cam = camera_for_points(np.concatenate(list(self._extra_points.values())), elevation_deg, azimuth_deg)
        self.scene_offset = point_camera(self.meshcat, cam, self._roots, show_grid)
        self.push_overlay()
        return cam

    def static_html(self, path: str | Path | None = None, frame: bool = True) -> str:
        """The standalone HTML page of the scene (no server needed to open it), written to
        ``path`` too (atomically) when given; ``frame`` first sets the side camera."""
        if frame:
            self.frame()
        html = self.meshcat.static_html().replace("</body>", self.overlay_html() + "\n</body>", 1)
        if path is not None:
            write_atomic(path, html)
            logger.info("wrote %s (%d bytes)", path, len(html))
        return html

    def jupyter_static(self, height: int = 400):
        """An inline notebook cell with a self-contained snapshot of the scene."""
        self.frame()
        return self.meshcat.render_static(height=height)
