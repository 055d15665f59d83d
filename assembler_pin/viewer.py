"""Meshcat viewing of the stack: poses, leg forces, helper arm, ghosts and animations.

:class:`StackViewer` draws the stack with :class:`pinocchio.visualize.MeshcatVisualizer`
and a visual geometry model parsed from the generated URDF (primitive shapes only:
plate discs and node spheres, motor and shaft cylinders, payload cube). It adds:

* leg colors by actuator force — blue (compression) ↔ gray (zero) ↔ red (tension),
  saturating at the configured limits (:func:`force_color`);
* markers on legs that violate a constraint;
* the helper arm of the initial-condition algorithm (violet links, dark violet joint
  clusters) from ``(n+2, 3)`` world points;
* a translucent green "ghost" of a second pose (e.g. the initial condition next to the
  optimized pose), drawn by a second visualizer under another meshcat path;
* every colour from the package's one colour language (:mod:`~assembler_pin.palette`);
* animations of a sequence of states (:func:`interpolate_states`), stored as meshcat
  animation tracks so that they play in a standalone HTML page too.

Everything is in the world frame O (z up) and SI units. The meshcat server is a
subprocess (:mod:`assembler_pin.meshcat_server`) whose page listens on 127.0.0.1 unless
another ``host`` is asked for; :meth:`StackViewer.close` stops it, and it stops by itself
when the Python process that started it ends, by any signal. The static page
(:meth:`StackViewer.static_html`) needs no server to be opened.

Display note: meshcat's orbit camera always turns about the world origin, so to frame
the stack the whole scene (stack, grid and axes) is translated by ``-target`` in the
viewer; :attr:`StackViewer.scene_offset` holds that translation. Poses passed to the
API are always world poses.
"""

from __future__ import annotations

import contextlib
import io
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import meshcat
import meshcat.animation
import meshcat.geometry as mg
import numpy as np
import numpy.typing as npt
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer

from . import palette
from .choices import FORCE_SCALES
from .exceptions import AssemblerError, ConvergenceError, ViewerError
from .geometry import DIMENSIONS
from .kinematics import PlateArrays, leg_state, plate_arrays, q_from_plates, stack_forward_kinematics
from .meshcat_server import DEFAULT_HOST, ServerProcess, start_server
from .model import WHOLE_DATA_MAX_PLATFORMS, AssemblerModel
from .naming import names, parse_name
from .signals import StopRequested, interrupt_on_signals
from .state import StackState, evaluate_state

__all__ = [
    "COMPRESSION_RGB",
    "GHOST_RGBA",
    "NEUTRAL_RGB",
    "TENSION_RGB",
    "StackViewer",
    "StopRequested",
    "camera_for_points",
    "force_color",
    "interpolate_states",
    "interrupt_on_signals",
]

logger = logging.getLogger(__name__)

COMPRESSION_RGB = np.array(palette.COMPRESSION)
"""Leg color at (or beyond) the compression limit."""
NEUTRAL_RGB = np.array(palette.NEUTRAL)
"""Leg color at zero force."""
TENSION_RGB = np.array(palette.TENSION)
"""Leg color at (or beyond) the tension limit."""
GHOST_RGBA = np.array(palette.rgba(palette.INITIAL, palette.GHOST_OPACITY))
"""Color of the translucent ghost pose (the paper draws the initial condition green)."""
ARM_LINK_RGBA = np.array(palette.rgba(palette.ARM))
"""Violet: the helper arm's links — a color no leg can take (legs run blue ↔ gray ↔ red)."""
ARM_CLUSTER_RGBA = np.array(palette.rgba(palette.ARM_JOINT))
"""Dark violet: the helper arm's joint clusters."""
PAYLOAD_RGBA = np.array(palette.rgba(palette.PAYLOAD))
"""Orange: the payload cube (solid in the shown pose, an orange wireframe in a ghost, so the
ghost's translucent green never tints it) and the rod joining it to the EE plate."""
PAYLOAD_ROD_RGBA = PAYLOAD_RGBA
"""The rod joining the payload to the EE plate (the payload's orange)."""
CARRIER_RGBA = np.array(palette.rgba(palette.CARRIER))
"""Slate: a carrier arm's meshes (a grey darker and bluer than a leg at zero force)."""
BACKGROUND_RGB = (np.array([0.97, 0.97, 0.96]), np.array([0.86, 0.87, 0.88]))
"""Neutral background, top and bottom."""
"""Leg color scales: ``limit`` saturates at the force limits, ``max`` at the state's max|F|,
``auto`` (default) at the larger of max|F| and :data:`FORCE_SCALE_FLOOR` × the smaller limit."""
FORCE_SCALE_FLOOR = 0.1
VIOLATION_RGBA = np.array(palette.rgba(palette.VIOLATION, 0.9))
FORCE_BAND_LEVELS = np.linspace(-1.0, 1.0, 11)
"""Force levels (fraction of the compression / tension limit) of an animation's leg sleeves."""
FORCE_BAND_LENGTH = 0.08
"""Length of an animated leg's force sleeve [m]."""
CAMERA_FOV_DEG = 75.0
"""Vertical field of view of meshcat's default perspective camera [deg]."""


def force_color(forces: npt.ArrayLike, max_tension: float, max_compression: float) -> np.ndarray:
    """RGB colors of actuator forces: blue (compression) ↔ gray (0) ↔ red (tension).

    Linear between the three anchor colors and saturating at the limits, so that the red
    channel grows and the blue channel falls monotonically with the force.

    Args:
        forces: actuator forces [N], tension positive, any shape.
        max_tension, max_compression: the limits [N] (positive numbers).

    Returns:
        Array of shape ``forces.shape + (3,)`` with components in [0, 1].
    """
    f = np.asarray(forces, dtype=float)
    if max_tension <= 0 or max_compression <= 0:
        raise AssemblerError("force limits for coloring must be positive")
    s = np.where(f >= 0, np.clip(f / max_tension, 0.0, 1.0), np.clip(f / max_compression, -1.0, 0.0))
    s = s[..., None]
    hot = NEUTRAL_RGB + s * (TENSION_RGB - NEUTRAL_RGB)
    cold = NEUTRAL_RGB - s * (COMPRESSION_RGB - NEUTRAL_RGB)
    return np.where(s >= 0, hot, cold)


@dataclass(frozen=True)
class Camera:
    """A camera pose for meshcat: look at ``target`` from ``position`` (world, [m])."""

    target: np.ndarray
    position: np.ndarray


def camera_for_points(
    points: npt.ArrayLike,
    elevation_deg: float = 12.0,
    azimuth_deg: float = -90.0,
    margin: float = 1.15,
    aspect: float = 4.0 / 3.0,
) -> Camera:
    """A side camera framing every point: z up, looking horizontally at the box centre.

    Args:
        points: (m, 3) world points to frame [m].
        elevation_deg: camera height angle above the horizontal [deg].
        azimuth_deg: direction of the camera from the target in the x–y plane [deg];
            -90° looks from -y towards +y (x to the right, z up: the paper's side view).
        margin: factor on the distance that just fits the points.
        aspect: expected width / height of the window.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    target = 0.5 * (lo + hi)
    radius_v = 0.5 * (hi[2] - lo[2])
    radius_h = 0.5 * max(hi[0] - lo[0], hi[1] - lo[1])
    half_fov = math.radians(CAMERA_FOV_DEG) / 2
    fit_v = radius_v / math.tan(half_fov)
    fit_h = radius_h / (math.tan(half_fov) * aspect)
    distance = margin * max(fit_v, fit_h, 0.2) + radius_h  # + radius_h: the near side is closer
    el, az = math.radians(elevation_deg), math.radians(azimuth_deg)
    direction = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    return Camera(target, target + distance * direction)


def _cylinder_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """4×4 transform placing meshcat's y-axis cylinder (centred) between points a and b."""
    d = b - a
    length = float(np.linalg.norm(d))
    y = d / length if length > 0 else np.array([0.0, 0.0, 1.0])
    helper = np.array([1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, z])
    T[:3, 3] = 0.5 * (a + b)
    return T


def _material(rgba: npt.ArrayLike) -> mg.MeshPhongMaterial:
    rgba = np.asarray(rgba, dtype=float)
    r, g, b = (round(255 * float(c)) for c in rgba[:3])
    mat = mg.MeshPhongMaterial(color=(r << 16) + (g << 8) + b)
    if rgba.shape[0] > 3 and rgba[3] < 1.0:
        mat.transparent = True
        mat.opacity = float(rgba[3])
    return mat


def _as_plates(am: AssemblerModel, pose: StackState | PlateArrays | Sequence | np.ndarray) -> PlateArrays:
    return pose.plates if isinstance(pose, StackState) else plate_arrays(am, pose)


def interpolate_states(
    am: AssemblerModel,
    start: StackState | PlateArrays | Sequence | np.ndarray,
    end: StackState | PlateArrays | Sequence | np.ndarray,
    steps: int = 30,
    end_tolerance: float = 1e-6,
) -> list[StackState]:
    """States along a straight line in leg-length space between two solved poses.

    Step k has lengths ``L0 + (k / (steps - 1)) (L1 - L0)``; its plate poses come from
    the stack forward kinematics (each step started from the previous one, base held at
    the start pose's base), and its statics from :func:`evaluate_state`.

    Args:
        start, end: the two poses (states or world plate poses); they must share plate 0.
        steps: number of states returned, both ends included (>= 2).
        end_tolerance: largest allowed distance [m] between the last FK pose and ``end``.

    Raises:
        ConvergenceError: the FK of a step failed (the message names the step), or the
            interpolation did not arrive at ``end``.
    """
    if steps < 2:
        raise AssemblerError(f"an animation needs at least 2 steps, got {steps}")
    p0, p1 = _as_plates(am, start), _as_plates(am, end)
    L0, L1 = leg_state(am, p0).lengths, leg_state(am, p1).lengths
    base = p0.se3(0)
    previous = p0
    states = []
    for k in range(steps):
        t = k / (steps - 1)
        fk = stack_forward_kinematics(am, (1.0 - t) * L0 + t * L1, base=base, guess=previous)
        if not fk.success:
            raise ConvergenceError(
                f"animation step {k}/{steps - 1} (t = {t:.3f}): stack forward kinematics failed: {fk.message}",
                fk.iterations,
                fk.residual,
            )
        previous = fk.plates
        states.append(evaluate_state(am, fk.plates))
    gap = float(np.abs(previous.p - p1.p).max() + np.abs(previous.R - p1.R).max())
    if gap > end_tolerance:
        raise ConvergenceError(
            f"the interpolated motion ends {gap:.3g} away from the end pose (another assembly mode, "
            "or the two poses do not share plate 0)",
            0,
            gap,
        )
    return states


class _CallerPlacedVisualizer(MeshcatVisualizer):
    """A ``MeshcatVisualizer`` whose bodies the caller places (:meth:`StackViewer.placements`):
    it never runs kinematics on its ``Data``, which is left empty for large stacks."""

    def updatePlacements(self, geometry_type) -> None:  # noqa: N802 - Pinocchio's name
        return None


class StackViewer:
    """Meshcat view of an Assembler.

    Args:
        am: the model to draw.
        viewer: an existing ``meshcat.Visualizer`` to draw into; default: start a meshcat
            server owned by this object (:func:`~assembler_pin.meshcat_server.start_server`),
            stopped by :meth:`close`, or with this process however it ends.
        prefix: meshcat path of the main stack.
        open: open the viewer's URL in a web browser.
        host: interface the started server's web page listens on: ``127.0.0.1`` (this
            machine only, the default) or e.g. ``0.0.0.0`` (every interface: anyone who
            can reach this machine sees the page).
        port: web port of the started server (default: the first free one from 7000).
        force_scale: default color scale of the legs (:data:`FORCE_SCALES`).

    Attributes:
        viz: the :class:`pinocchio.visualize.MeshcatVisualizer` of the main stack.
        server: the meshcat server subprocess this viewer started (None when borrowed).
        meshcat: the underlying ``meshcat.Visualizer`` (``viewer.meshcat.jupyter_cell()``
            or :meth:`jupyter_static` for notebooks).
        scene_offset: translation applied to the whole scene for framing [m].
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
    ) -> None:
        if force_scale not in FORCE_SCALES:
            raise ViewerError(f"force_scale must be one of {', '.join(FORCE_SCALES)}, got {force_scale!r}")
        self.force_scale = force_scale
        self.am = am
        # Up to WHOLE_DATA_MAX_PLATFORMS the bodies are placed by Pinocchio's kinematics of the
        # whole stack; above, its Data (cubic in n) is never made and every visual is placed in
        # closed form from the plate poses and leg joint centres (:meth:`placements`).
        self.whole_stack_kinematics = am.n <= WHOLE_DATA_MAX_PLATFORMS
        self.server: ServerProcess | None = None
        if viewer is None:
            self.server = start_server(host, port)
            try:
                with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL
                    viewer = meshcat.Visualizer(zmq_url=self.server.zmq_url)
            except BaseException:
                self.server.stop()
                raise
        self.meshcat: meshcat.Visualizer = viewer
        self.visual_model = pin.buildGeomFromUrdfString(am.model, am.urdf_text, pin.GeometryType.VISUAL)
        self._geometry_frames = self._index_geometry_frames()
        self.prefix = prefix
        self.scene_offset = np.zeros(3)
        self._ghosts: dict[str, MeshcatVisualizer] = {}
        self._extra_points: dict[str, np.ndarray] = {}
        self._roots: list[str] = [prefix, f"{prefix}_violations"]
        self.state: StackState | None = None
        self.title = ""
        self.force_range = (am.config.leg.max_tension, am.config.leg.max_compression)
        self._animated = False
        self.viz = self._make_visualizer(prefix)
        self._leg_geoms = self._index_leg_geometries()
        if open:
            self.meshcat.open()
        logger.info("meshcat viewer at %s", self.url)

    # ------------------------------------------------------------------ plumbing
    def _make_visualizer(self, root: str, rgba: npt.ArrayLike | None = None) -> MeshcatVisualizer:
        if self.whole_stack_kinematics:
            viz = MeshcatVisualizer(self.am.model, None, self.visual_model, copy_models=False)
        else:  # an empty Data stands in: nothing runs kinematics on it
            viz = _CallerPlacedVisualizer(self.am.model, None, self.visual_model, copy_models=False, data=pin.Data())
        viz.initViewer(viewer=self.meshcat)
        viz.loadViewerModel(
            rootNodeName=root, visual_color=None if rgba is None else [float(c) for c in np.asarray(rgba)]
        )
        return viz

    def _index_leg_geometries(self) -> dict[tuple[int, int], list[int]]:
        """Geometry ids of the motor and shaft of every leg, keyed by (platform, leg)."""
        frames = self.am.model.frames
        out: dict[tuple[int, int], list[int]] = {}
        wanted = {
            names.leg(j, i, part): (j, i) for j in range(self.am.n) for i in range(6) for part in ("motor", "shaft")
        }
        for gid, g in enumerate(self.visual_model.geometryObjects):
            key = wanted.get(frames[g.parentFrame].name)
            if key is not None:
                out.setdefault(key, []).append(gid)
        return out

    def _index_geometry_frames(self) -> list[tuple[str, tuple[int, ...], np.ndarray]]:
        """For each visual: its body (``plate`` k, ``motor``/``shaft`` (j, i) or ``payload``)
        and its placement in the frame of the joint that moves it (4×4), as Pinocchio
        stores it: the plate's, the universal joint's (motor) or the actuator's (shaft)."""
        frames = self.am.model.frames
        out: list[tuple[str, tuple[int, ...], np.ndarray]] = []
        for g in self.visual_model.geometryObjects:
            name = frames[g.parentFrame].name
            local = g.placement.homogeneous
            body = parse_name(name)
            out.append((body.kind, body.indices, local))
        return out

    def placements(self, pose: StackState | PlateArrays) -> list[np.ndarray]:
        """World placement (4×4) of every visual for a pose, in ``visual_model`` order.

        With the whole-stack kinematics, Pinocchio's; otherwise in closed form: plates and
        payload from the plate poses, each leg's motor frame at its universal-joint centre and
        its shaft frame at its ball-joint centre, both with z along the leg (motor and shaft
        are cylinders about that axis, so the turn about it does not show).
        """
        plates = _as_plates(self.am, pose)
        if self.whole_stack_kinematics:
            model, data = self.viz.model, self.viz.data
            vdata = self.viz.visual_data
            pin.forwardKinematics(model, data, q_from_plates(self.am, plates))
            pin.updateGeometryPlacements(model, data, self.visual_model, vdata)
            return [vdata.oMg[k].homogeneous for k in range(len(self._geometry_frames))]
        legs = pose.legs if isinstance(pose, StackState) else leg_state(self.am, plates)
        bottom, top = legs.bottom_points, legs.top_points
        axis = (top - bottom) / np.linalg.norm(top - bottom, axis=-1, keepdims=True)
        T_plates = plates.as_matrices()
        out = []
        for body, idx, local in self._geometry_frames:
            if body == "plate":
                frame = T_plates[idx[0]]
            elif body == "payload":  # fixed to the EE plate: its placement is in the plate's joint frame
                frame = T_plates[-1]
            else:
                frame = _frame_along(axis[idx], bottom[idx] if body == "motor" else top[idx])
            out.append(frame @ local)
        return out

    def _place(self, viz: MeshcatVisualizer, pose: StackState | PlateArrays) -> None:
        """Put every body of ``viz`` at ``pose``."""
        if self.whole_stack_kinematics:
            viz.display(q_from_plates(self.am, _as_plates(self.am, pose)))
            return
        for g, T in zip(self.visual_model.geometryObjects, self.placements(pose), strict=True):
            self.meshcat[viz.getViewerNodeName(g, pin.GeometryType.VISUAL)].set_transform(T)

    @property
    def url(self) -> str:
        """URL of the live viewer (served on ``host``, 127.0.0.1 by default)."""
        return self.meshcat.url()

    def close(self) -> None:
        """Stop the meshcat server this viewer started and wait for it to end.

        A borrowed viewer (``viewer=`` given) is left running. Safe to call twice. The
        server also stops by itself when this Python process ends, however it ends
        (see :mod:`assembler_pin.meshcat_server`).
        """
        if self.server is not None:
            with contextlib.suppress(Exception):
                self.meshcat.window.zmq_socket.close(linger=0)
            self.server.stop()

    def __enter__(self) -> StackViewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ drawing
    def display(
        self,
        pose: StackState | PlateArrays | Sequence | np.ndarray,
        color_forces: bool = True,
        mark_violations: bool = True,
        force_scale: str | None = None,
    ) -> StackState:
        """Show a pose; color each leg by its force and mark violating legs.

        An animation stored before (:meth:`animate`) is removed first: it moves the same
        bodies and would otherwise replay over this pose in the live and static pages.

        Args:
            pose: a :class:`StackState`, or world plate poses (their state is computed).
            color_forces: color motor and shaft by the actuator force (else URDF colors).
            force_scale: where the colors saturate (:data:`FORCE_SCALES`; default the
                viewer's :attr:`force_scale`); the numbers are in :attr:`force_range` and on
                the page's color bar.
            mark_violations: put a yellow marker at the middle of every leg that
                violates a constraint (length, deflection, force, rise), at the meshcat
                path ``{prefix}_violations/sp{j}_leg{i}`` (0-based, as the URDF's names
                and :mod:`~assembler_pin.labels`: ``sp1_leg2`` marks ``SP1 leg 2``).

        Returns:
            The state shown.
        """
        state = pose if isinstance(pose, StackState) else evaluate_state(self.am, pose)
        self.state = state
        self._clear_animation()
        self._place(self.viz, state)
        self.force_range = self.color_scale(state, force_scale or self.force_scale)
        colors = force_color(state.forces, *self.force_range)
        for (j, i), gids in self._leg_geoms.items():
            for gid in gids:
                g = self.visual_model.geometryObjects[gid]
                rgba = [*colors[j, i], 1.0] if color_forces else list(g.meshColor)
                self.viz.loadViewerGeometryObject(g, pin.GeometryType.VISUAL, rgba)
        self._place(self.viz, state)  # reloaded objects keep their transforms; refresh anyway
        marks = self.meshcat[f"{self.prefix}_violations"]
        marks.delete()
        if mark_violations:
            for j, i in self.violating_legs(state):
                mid = 0.5 * (state.legs.bottom_points[j, i] + state.legs.top_points[j, i])
                node = marks[names.leg(j, i)]
                node.set_object(mg.Sphere(2.2 * DIMENSIONS.motor_radius), _material(VIOLATION_RGBA))
                node.set_transform(_translation(mid))
        self._show_payload_rod(state.plates)
        self._extra_points["stack"] = self._stack_points(state)
        return state

    def color_scale(self, state: StackState, force_scale: str = "auto") -> tuple[float, float]:
        """(tension, compression) [N] at which the leg colors saturate (see :data:`FORCE_SCALES`)."""
        if force_scale not in FORCE_SCALES:
            raise ViewerError(f"force_scale must be one of {', '.join(FORCE_SCALES)}, got {force_scale!r}")
        leg = self.am.config.leg
        if force_scale == "limit":
            return leg.max_tension, leg.max_compression
        peak = max(state.max_abs_force, 1e-9)
        if force_scale == "auto":
            peak = max(peak, FORCE_SCALE_FLOOR * min(leg.max_tension, leg.max_compression))
        return peak, peak

    def _show_payload_rod(self, plates: PlateArrays) -> None:
        """A thin rod from the EE plate's centre to the payload, so it does not float."""
        offset = self.am.config.payload.offset
        node = self.meshcat[f"{self.prefix}_payload_rod"]["rod"]  # the root carries the framing shift
        if offset <= 0 or self.am.config.payload.mass <= 0:
            node.delete()
            return
        a = plates.p[-1]
        b = plates.R[-1] @ np.array([0.0, 0.0, offset]) + a
        node.set_object(mg.Cylinder(offset, 0.4 * DIMENSIONS.motor_radius), _material(PAYLOAD_ROD_RGBA))
        node.set_transform(_cylinder_between(a, b))
        if f"{self.prefix}_payload_rod" not in self._roots:
            self._roots.append(f"{self.prefix}_payload_rod")

    def set_title(self, title: str) -> None:
        """The title of the page's overlay (e.g. the scenario or goal and max|F|)."""
        self.title = str(title)
        self.push_overlay()

    def push_overlay(self) -> None:
        """Send the overlay to the live page (its server is ours: a borrowed meshcat server
        has no overlay; the standalone page always embeds it, see :meth:`static_html`)."""
        if self.server is None:
            return
        from .meshcat_server import SET_OVERLAY

        socket = self.meshcat.window.zmq_socket
        socket.send_multipart([SET_OVERLAY, self.overlay_html().encode("utf-8")])
        socket.recv()

    def overlay_html(self) -> str:
        """The page's overlay: title, legend of every color and marker drawn, and the
        color bar of the leg forces with its numbers [N]."""
        import html as html_lib

        tension, compression = self.force_range
        items = [
            (_hex(TENSION_RGB), "leg in tension (+)"),
            (_hex(COMPRESSION_RGB), "leg in compression (−)"),
            (_hex(NEUTRAL_RGB), "leg at 0 N"),
        ]
        if self._ghosts:
            items.append((_hex(GHOST_RGBA[:3]), "initial pose (ghost)"))
        if any(r == "helper_arm" for r in self._roots):
            items.append((_hex(ARM_LINK_RGBA[:3]), "helper arm"))
        if self.state is not None and self.violating_legs(self.state):
            items.append((_hex(VIOLATION_RGBA[:3]), "yellow ball: leg violating a limit"))
        if getattr(self, "_carrier_name", None):
            items.append((_hex(CARRIER_RGBA[:3]), f"carrier arm: {self._carrier_name}"))
        if self.am.config.payload.mass > 0:
            items.append((_hex(PAYLOAD_RGBA[:3]), f"payload {self.am.config.payload.mass:g} kg"))
        legend = "".join(
            f'<div><span style="display:inline-block;width:12px;height:12px;background:{c};margin-right:6px;'
            f'border:1px solid #555"></span>{html_lib.escape(t)}</div>'
            for c, t in items
        )
        blue, gray, red = (_hex(rgb) for rgb in (COMPRESSION_RGB, NEUTRAL_RGB, TENSION_RGB))
        bar = (
            f'<div id="assembler-colorbar" style="margin-top:8px">leg force [N]'
            f'<div style="height:12px;width:220px;background:linear-gradient(to right,{blue},{gray},{red});'
            f'border:1px solid #555"></div><div style="display:flex;justify-content:space-between;width:222px">'
            f"<span>−{compression:.0f}</span><span>0</span><span>+{tension:.0f}</span></div></div>"
        )
        title = html_lib.escape(self.title or "Assembler")
        return (
            '<div id="assembler-overlay" style="position:absolute;top:8px;left:8px;z-index:10;'
            "max-width:330px;background:rgba(255,255,255,0.8);padding:6px 8px;border-radius:4px;font:12px sans-serif;"
            f'color:#222;pointer-events:none"><div id="assembler-title" style="font-weight:bold;'
            f'margin-bottom:6px">{title}</div><div id="assembler-legend">{legend}</div>{bar}</div>'
        )

    @staticmethod
    def violating_legs(state: StackState) -> list[tuple[int, int]]:
        """(platform, leg) of every leg with at least one violation, sorted."""
        return sorted({(v.platform, v.leg) for v in state.violations if v.platform is not None and v.leg is not None})

    def drawn_leg_endpoints(self) -> tuple[np.ndarray, np.ndarray]:
        """World joint centres of the legs as drawn: (n, 6, 3) bottom and top [m].

        Read back from the visualizer's own kinematics (motor frame origin = universal
        joint centre, shaft frame origin = ball joint centre); above
        ``WHOLE_DATA_MAX_PLATFORMS``, the joint centres the closed-form placements use.
        """
        if not self.whole_stack_kinematics:
            if self.state is None:
                raise AssemblerError("nothing drawn yet: call display() first")
            return self.state.legs.bottom_points.copy(), self.state.legs.top_points.copy()
        model, data = self.viz.model, self.viz.data
        pin.updateFramePlacements(model, data)
        bottom = np.zeros((self.am.n, 6, 3))
        top = np.zeros((self.am.n, 6, 3))
        for j in range(self.am.n):
            for i in range(6):
                bottom[j, i] = data.oMf[model.getFrameId(names.leg(j, i, "motor"))].translation
                top[j, i] = data.oMf[model.getFrameId(names.leg(j, i, "shaft"))].translation
        return bottom, top

    def show_ghost(
        self,
        pose: StackState | PlateArrays | Sequence | np.ndarray,
        name: str = "initial",
        rgba: npt.ArrayLike = GHOST_RGBA,
    ) -> None:
        """Draw a second pose as a translucent ghost (default: green, 30 % opacity).

        It is a second ``MeshcatVisualizer`` under the meshcat path ``{prefix}_{name}``. Its
        payload is an orange wireframe, not a translucent cube: the two payloads overlap
        (same goal), and a translucent one in front would tint the solid payload olive.
        """
        plates = _as_plates(self.am, pose)
        if name not in self._ghosts:
            self._ghosts[name] = self._make_visualizer(f"{self.prefix}_{name}", rgba)
            self._roots.append(f"{self.prefix}_{name}")
            self._wireframe_payload(self._ghosts[name])
        self._place(self._ghosts[name], plates)
        self._extra_points[f"ghost_{name}"] = self._stack_points(plates)

    def _wireframe_payload(self, viz: MeshcatVisualizer) -> None:
        """Redraw the payload cube of ``viz`` as an opaque orange wireframe (placements are kept:
        meshcat keeps a node's transform when its object is replaced)."""
        for g in self.visual_model.geometryObjects:
            if self.am.model.frames[g.parentFrame].name != names.payload:
                continue
            material = _material(PAYLOAD_RGBA)
            material.wireframe = True
            self.meshcat[viz.getViewerNodeName(g, pin.GeometryType.VISUAL)].set_object(viz.loadPrimitive(g), material)

    def show_helper_arm(self, points: npt.ArrayLike, name: str = "helper_arm") -> None:
        """Draw the helper arm: violet links between consecutive points, dark violet joint clusters.

        Args:
            points: (n+2, 3) world points [m]: base, the n joint clusters, tip.
        """
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2 or not np.all(np.isfinite(pts)):
            raise AssemblerError(f"helper arm points must be a finite (m >= 2, 3) array, got shape {pts.shape}")
        root = self.meshcat[name]
        root.delete()
        link_r = 0.6 * DIMENSIONS.motor_radius
        for k in range(pts.shape[0] - 1):
            length = float(np.linalg.norm(pts[k + 1] - pts[k]))
            if length < 1e-9:
                continue
            node = root[f"link{k}"]
            node.set_object(mg.Cylinder(length, link_r), _material(ARM_LINK_RGBA))
            node.set_transform(_cylinder_between(pts[k], pts[k + 1]))
        for k in range(1, pts.shape[0] - 1):
            node = root[f"cluster{k}"]
            node.set_object(mg.Sphere(2.0 * DIMENSIONS.node_sphere_radius), _material(ARM_CLUSTER_RGBA))
            node.set_transform(_translation(pts[k]))
        for k in (0, pts.shape[0] - 1):
            node = root[f"end{k}"]
            node.set_object(mg.Sphere(1.2 * link_r), _material(ARM_LINK_RGBA))
            node.set_transform(_translation(pts[k]))
        self._extra_points[name] = pts
        if name not in self._roots:
            self._roots.append(name)

    def show_points(self, name: str, points: npt.ArrayLike, colors: npt.ArrayLike, size: float = 0.03) -> None:
        """A point cloud under the meshcat path ``name``: (N, 3) world points [m] and (N, 3)
        RGB colors in [0, 1]; the camera frames it with the rest."""
        pts = np.asarray(points, dtype=float)
        rgb = np.asarray(colors, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3 or rgb.shape != pts.shape or not np.all(np.isfinite(pts)):
            raise ViewerError(f"points and colors must be finite (N, 3) arrays, got {pts.shape} and {rgb.shape}")
        node = self.meshcat[name]
        node.set_object(mg.PointCloud(position=pts.T.astype(np.float32), color=rgb.T.astype(np.float32), size=size))
        if name not in self._roots:
            self._roots.append(name)
        self._extra_points[name] = pts

    def show_carrier(self, carrier, q: npt.ArrayLike, name: str = "carrier") -> None:
        """Draw a carrier arm (:class:`~assembler_pin.carrier.Carrier`) with its meshes at
        joint angles ``q``, under the meshcat path ``name``."""
        q = carrier.check_q(q)
        viz = MeshcatVisualizer(carrier.model, None, carrier.visual_model)
        viz.initViewer(viewer=self.meshcat)
        viz.loadViewerModel(rootNodeName=name)
        _paint_meshes(viz, CARRIER_RGBA)
        viz.display(q)
        self._carrier_viz = viz
        if name not in self._roots:
            self._roots.append(name)
        self._extra_points[name] = carrier.joint_points(q)
        self._carrier_name = carrier.name

    def show_comparison(
        self,
        initial: StackState | None,
        optimized: StackState | None,
        arm_points: npt.ArrayLike | None = None,
    ) -> None:
        """The paper's comparison: optimized pose solid (force colors), initial as a ghost.

        Either pose may be missing (None); with only the initial pose it is drawn solid.
        """
        if optimized is not None:
            self.display(optimized)
            if initial is not None:
                self.show_ghost(initial)
        elif initial is not None:
            self.display(initial)
        else:
            raise AssemblerError("nothing to show: both the initial and the optimized state are missing")
        if arm_points is not None:
            self.show_helper_arm(arm_points)
        self.frame()

    def animate(
        self,
        states: Sequence[StackState | PlateArrays],
        fps: float = 15.0,
        repetitions: int = 1,
        play: bool = True,
        color_forces: bool = False,
    ) -> None:
        """Store the sequence as a meshcat animation (plays in the live and static viewer).

        The stack is displayed at the first state (leg colors of that state); each frame
        moves every body of the main stack, and the page ends on the last state. A later
        :meth:`display` (or :meth:`show_comparison`) removes the animation. Build
        ``states`` with :func:`interpolate_states` (or, for a planned trajectory,
        :func:`~assembler_pin.motion.timing.trajectory_states`).

        Args:
            fps: frames per second of playback.
            color_forces: also animate each leg's color with its force in every frame
                (``states`` must then be :class:`StackState` objects).
        """
        if len(states) < 2:
            raise AssemblerError("an animation needs at least two states")
        if color_forces and not all(isinstance(st, StackState) for st in states):
            raise AssemblerError("color_forces needs StackState frames (their forces)")
        if color_forces:
            self._make_force_bands()
        first = states[0]
        self.display(first if isinstance(first, StackState) else evaluate_state(self.am, first))
        anim = meshcat.animation.Animation(default_framerate=fps)
        vmodel = self.visual_model
        for k, st in enumerate(states):
            plates = _as_plates(self.am, st)
            placed = self.placements(st)
            with anim.at_frame(self.meshcat, k) as frame:
                for g, T in zip(vmodel.geometryObjects, placed, strict=True):
                    frame[self.viz.getViewerNodeName(g, pin.GeometryType.VISUAL)].set_transform(T)
                if self.am.config.payload.offset > 0 and self.am.config.payload.mass > 0:
                    rod_end = plates.R[-1] @ np.array([0.0, 0.0, self.am.config.payload.offset]) + plates.p[-1]
                    frame[f"{self.prefix}_payload_rod"]["rod"].set_transform(_cylinder_between(plates.p[-1], rod_end))
                if color_forces:
                    assert isinstance(st, StackState)  # checked above
                    self._force_band_frame(frame, st)
            self._extra_points[f"anim{k}"] = self._stack_points(plates)
        if color_forces and f"{self.prefix}_force_bands" not in self._roots:
            self._roots.append(f"{self.prefix}_force_bands")
        self.meshcat.set_animation(anim, play=play, repetitions=repetitions)
        self._animated = True
        self._place(self.viz, first)

    def _make_force_bands(self) -> None:
        """One sleeve per leg and force level, hidden; :meth:`_force_band_frame` shows one.

        meshcat animates transforms and visibility but not material colors, so a leg's
        force color in an animation is a sleeve of the level's color around its middle.
        """
        root = self.meshcat[f"{self.prefix}_force_bands"]
        root.delete()
        leg = self.am.config.leg
        levels = FORCE_BAND_LEVELS
        forces = np.where(levels >= 0, levels * leg.max_tension, levels * leg.max_compression)
        colors = force_color(forces, leg.max_tension, leg.max_compression)
        shape = mg.Cylinder(FORCE_BAND_LENGTH, 1.3 * DIMENSIONS.motor_radius)
        for j in range(self.am.n):
            for i in range(6):
                for k, rgb in enumerate(colors):
                    node = root[names.leg(j, i)][f"level{k}"]
                    node.set_object(shape, _material([*rgb, 1.0]))
                    node.set_property("visible", False)

    def _force_band_frame(self, frame, state: StackState) -> None:
        """Place and show, in one animation frame, the sleeve of each leg's force level."""
        leg = self.am.config.leg
        fraction = np.where(state.forces >= 0, state.forces / leg.max_tension, state.forces / leg.max_compression)
        level = np.abs(FORCE_BAND_LEVELS[None, None, :] - np.clip(fraction, -1, 1)[..., None]).argmin(axis=-1)
        root = frame[f"{self.prefix}_force_bands"]
        for j in range(self.am.n):
            for i in range(6):
                T = _cylinder_between(state.legs.bottom_points[j, i], state.legs.top_points[j, i])
                for k in range(len(FORCE_BAND_LEVELS)):
                    node = root[names.leg(j, i)][f"level{k}"]
                    node.set_property("visible", "boolean", bool(k == level[j, i]))
                    if k == level[j, i]:
                        node.set_transform(T)

    def _clear_animation(self) -> None:
        """Replace a stored animation by an empty one (meshcat has no command to delete it).

        Sent before any new transform: in the browser, stopping an animation restores the
        bodies to where they were when it started.
        """
        if not self._animated:
            return
        self.meshcat.set_animation(meshcat.animation.Animation(), play=False)
        self.meshcat[f"{self.prefix}_force_bands"].delete()
        self._animated = False
        for key in [k for k in self._extra_points if k.startswith("anim")]:
            del self._extra_points[key]

    # ------------------------------------------------------------------ camera / export
    def _stack_points(self, pose: StackState | PlateArrays) -> np.ndarray:
        """World points bounding the drawn stack: plate rims, joint centres, payload."""
        plates = _as_plates(self.am, pose)
        r = self.am.config.plate.node_radius + DIMENSIONS.node_sphere_radius
        ang = np.linspace(0, 2 * np.pi, 12, endpoint=False)
        rim = np.stack([r * np.cos(ang), r * np.sin(ang), np.zeros_like(ang)], axis=1)
        pts = [np.einsum("kab,mb->kma", plates.R, rim).reshape(-1, 3) + np.repeat(plates.p, len(ang), axis=0)]
        half = 0.5 * DIMENSIONS.payload_size
        payload = plates.R[-1] @ np.array([0.0, 0.0, self.am.config.payload.offset + half]) + plates.p[-1]
        pts.append(payload[None, :])
        return np.concatenate(pts)

    def frame(
        self,
        elevation_deg: float = 12.0,
        azimuth_deg: float = -90.0,
        show_grid: bool = True,
    ) -> Camera:
        """Point the camera at everything drawn, from the side (z up), framing it whole.

        meshcat's camera orbits the world origin, so the scene is translated by
        ``-target`` (stored in :attr:`scene_offset`) and the camera placed relative to it.
        """
        if not self._extra_points:
            raise AssemblerError("nothing drawn yet: call display() first")
        cam = camera_for_points(np.concatenate(list(self._extra_points.values())), elevation_deg, azimuth_deg)
        self.scene_offset = -cam.target
        shift = _translation(self.scene_offset)
        for root in ["/Grid", "/Axes", *self._roots]:
            self.meshcat[root].set_transform(shift)
        rel = cam.position - cam.target
        self.meshcat["/Cameras/default"].set_transform(np.eye(4))
        # three.js is y-up: world (x, y, z) -> (x, z, -y)
        self.meshcat["/Cameras/default/rotated/<object>"].set_property("position", [rel[0], rel[2], -rel[1]])
        self.meshcat["/Grid"].set_property("visible", show_grid)
        self.meshcat["/Background"].set_property("top_color", BACKGROUND_RGB[0].tolist())
        self.meshcat["/Background"].set_property("bottom_color", BACKGROUND_RGB[1].tolist())
        self.push_overlay()
        return cam

    def static_html(self, path: str | Path | None = None, frame: bool = True) -> str:
        """The standalone HTML page of the scene (no server needed to open it).

        Args:
            path: write the page there too (atomically: a reader sees the whole page or none).
            frame: set the side camera framing the stack first (:meth:`frame`).
        """
        if frame:
            self.frame()
        html = self.meshcat.static_html()
        html = html.replace("</body>", self.overlay_html() + "\n</body>", 1)
        if path is not None:
            from .files import write_atomic

            write_atomic(path, html)
            logger.info("wrote %s (%d bytes)", path, len(html))
        return html

    def jupyter_static(self, height: int = 400):
        """An inline notebook cell with a self-contained snapshot (needs no browser link
        to the server: the scene is embedded)."""
        self.frame()
        return self.meshcat.render_static(height=height)


def _paint_meshes(viz: MeshcatVisualizer, rgba: npt.ArrayLike) -> None:
    """Redraw every mesh-file visual of ``viz`` in one colour (a mesh file's own materials,
    e.g. a carrier's Collada colours, would otherwise be drawn; unscaled meshes only)."""
    loaders = {"dae": mg.DaeMeshGeometry, "stl": mg.StlMeshGeometry, "obj": mg.ObjMeshGeometry}
    for g in viz.visual_model.geometryObjects:
        loader = loaders.get(str(g.meshPath).rsplit(".", 1)[-1].lower())
        if loader is None or not np.allclose(g.meshScale, 1.0):
            continue
        node = viz.viewer[viz.getViewerNodeName(g, pin.GeometryType.VISUAL)]
        node.set_object(loader.from_file(g.meshPath), _material(rgba))


def _frame_along(z: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """A 4×4 frame at ``origin`` whose z axis is the unit vector ``z``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = origin
    return T


def _hex(rgb: npt.ArrayLike) -> str:
    """CSS color of an RGB(A) triple in [0, 1] (:func:`~assembler_pin.palette.hex_color`)."""
    return palette.hex_color(tuple(np.asarray(rgb, dtype=float)[:3]))


def _translation(p: npt.ArrayLike) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = np.asarray(p, dtype=float)
    return T
