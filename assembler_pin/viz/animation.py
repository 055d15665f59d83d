"""Motions for the viewer: states interpolated in leg-length space, and the animated force sleeves.

meshcat animates transforms, scales and visibility but not material colours, so a leg's force
colour in an animation is a sleeve of its force level's colour over the leg, joint to joint:
one hidden sleeve per leg and level (:func:`make_force_bands`), the one of the frame's level
shown and stretched to the leg's length (:func:`force_band_frame`). The levels span the
colour scale of the whole animation (:func:`animation_scale`), so that the colours and the
colour bar say the same. World frame O, metres, newtons.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import SimpleNamespace
from typing import TYPE_CHECKING

import meshcat.animation
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin

from ..common.naming import names
from ..exceptions import AssemblerError, ConvergenceError
from ..kinematics import PlateArrays, leg_state, leg_vectors, stack_forward_kinematics
from ..model.assembler import AssemblerModel
from ..model.geometry import DIMENSIONS
from ..state import StackState, evaluate_state
from .camera import cylinder_between
from .colors import color_scale, force_color, material
from .drawing import payload_rod_transform
from .placements import as_plates

if TYPE_CHECKING:
    from ..walk import WalkResult

__all__ = [
    "FORCE_BAND_COVER",
    "FORCE_BAND_LENGTH",
    "FORCE_BAND_LEVELS",
    "WALK_PHASE_RGB",
    "PhaseSpan",
    "WalkFrame",
    "animation_scale",
    "band_levels",
    "build_animation",
    "build_walk_animation",
    "force_band_frame",
    "interpolate_states",
    "make_force_bands",
    "make_phase_labels",
    "make_walk_markers",
    "phase_spans",
    "walk_frames",
]

FORCE_BAND_LEVELS = np.linspace(-1.0, 1.0, 21)
"""Force levels (fraction of the colour scale's compression / tension end) of an animation's
leg sleeves."""
FORCE_BAND_LENGTH = 0.08
"""Length of an animated leg's force sleeve as made [m]; each frame stretches it to
:data:`FORCE_BAND_COVER` of the leg."""
FORCE_BAND_COVER = 0.94
"""Fraction of a leg's joint-to-joint length its force sleeve covers in an animation."""


def animation_scale(forces: Sequence[np.ndarray], leg, force_scale: str = "auto") -> tuple[float, float]:
    """(tension, compression) [N] where the colours of an animation saturate: the rule of
    :func:`~assembler_pin.viz.colors.color_scale` applied to the largest force of every frame."""
    peak = max((float(np.abs(f).max()) for f in forces), default=0.0)
    return color_scale(SimpleNamespace(max_abs_force=peak), leg, force_scale)


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
    p0, p1 = as_plates(am, start), as_plates(am, end)
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


def build_animation(
    viewer,
    states: Sequence[StackState | PlateArrays],
    fps: float,
    color_forces: bool,
    scale: tuple[float, float] | None = None,
):
    """The meshcat animation of ``states`` in a :class:`~assembler_pin.viz.StackViewer`: frame k
    moves every body of its main stack and the payload rod to ``states[k]`` and, with
    ``color_forces``, shows each leg's force sleeve (built by :func:`make_force_bands` with the
    same ``scale``, (tension, compression) [N]; default the force limits)."""
    am = viewer.am
    anim = meshcat.animation.Animation(default_framerate=fps)
    rod = am.config.payload.offset > 0 and am.config.payload.mass > 0
    for k, state in enumerate(states):
        with anim.at_frame(viewer.meshcat, k) as frame:
            for g, T in zip(viewer.visual_model.geometryObjects, viewer.placements(state), strict=True):
                frame[viewer.viz.getViewerNodeName(g, pin.GeometryType.VISUAL)].set_transform(T)
            plates = as_plates(am, state)
            if rod:
                T_rod = payload_rod_transform(am, plates.R[-1], plates.p[-1])
                frame[viewer.scene_path("payload_rod")]["rod"].set_transform(T_rod)
            if color_forces and isinstance(state, StackState):
                force_band_frame(frame[viewer.scene_path("force_bands")], am, state, scale)
    return anim


def _scale(am: AssemblerModel, scale: tuple[float, float] | None) -> tuple[float, float]:
    leg = am.config.leg
    return (leg.max_tension, leg.max_compression) if scale is None else (float(scale[0]), float(scale[1]))


def make_force_bands(root, am: AssemblerModel, scale: tuple[float, float] | None = None) -> None:
    """One hidden sleeve per leg and force level under the meshcat node ``root``, at
    ``root/<leg name>/level<k>`` (:func:`force_band_frame` shows one per frame); the levels
    span ``scale`` = (tension, compression) [N] (default the force limits)."""
    root.delete()
    tension, compression = _scale(am, scale)
    levels = FORCE_BAND_LEVELS
    forces = np.where(levels >= 0, levels * tension, levels * compression)
    colors = force_color(forces, tension, compression)
    shape = mg.Cylinder(FORCE_BAND_LENGTH, 1.3 * DIMENSIONS.motor_radius)
    for j in range(am.n):
        for i in range(6):
            for k, rgb in enumerate(colors):
                node = root[names.leg(j, i)][f"level{k}"]
                node.set_object(shape, material([*rgb, 1.0]))
                node.set_property("visible", False)


def force_band_frame(root, am: AssemblerModel, state: StackState, scale: tuple[float, float] | None = None) -> None:
    """In one animation frame (``root`` its node of the sleeves), place, stretch over the leg
    and show the sleeve of each leg's force level on ``scale`` and hide the others."""
    _band_frame(root, am, state.forces, state.legs.bottom_points, state.legs.top_points, scale)


def band_levels(am: AssemblerModel, forces: np.ndarray, scale: tuple[float, float] | None = None) -> np.ndarray:
    """(n, 6) the sleeve level (index into :data:`FORCE_BAND_LEVELS`) of each leg force [N]."""
    tension, compression = _scale(am, scale)
    fraction = np.where(forces >= 0, forces / tension, forces / compression)
    return np.abs(FORCE_BAND_LEVELS[None, None, :] - np.clip(fraction, -1, 1)[..., None]).argmin(axis=-1)


def _band_frame(
    root,
    am: AssemblerModel,
    forces: np.ndarray,
    bottom: np.ndarray,
    top: np.ndarray,
    scale: tuple[float, float] | None = None,
) -> None:
    """:func:`force_band_frame` of leg forces (n, 6) [N] and joint centres (n, 6, 3) [m]."""
    level = band_levels(am, forces, scale)
    for j in range(am.n):
        for i in range(6):
            T = cylinder_between(bottom[j, i], top[j, i])
            stretch = FORCE_BAND_COVER * float(np.linalg.norm(top[j, i] - bottom[j, i])) / FORCE_BAND_LENGTH
            for k in range(len(FORCE_BAND_LEVELS)):
                node = root[names.leg(j, i)][f"level{k}"]
                node.set_property("visible", "boolean", bool(k == level[j, i]))
                if k == level[j, i]:
                    node.set_transform(T)
                    node.set_property("scale", "vector3", [1.0, stretch, 1.0])


# ---------------------------------------------------------------------- the walk
WALK_PHASE_RGB = {
    "reach": np.array([0.106, 0.620, 0.467]),
    "transfer": np.array([0.459, 0.439, 0.702]),
    "swing": np.array([0.906, 0.161, 0.541]),
}
"""Colour of the held-foot marker in each kind of walk phase (no leg takes these: legs run
blue ↔ grey ↔ red)."""
FOOTHOLD_RGBA = np.array([0.55, 0.27, 0.07, 0.8])
"""A foothold's disc (the floor's brown)."""
HELD_PLATES = {"base": (0,), "ee": (-1,), "both": (0, -1)}
"""The plates held in each support of a walk phase (index into plates 0..n)."""
_DISC = pin.SE3(pin.exp3(np.array([0.5 * np.pi, 0.0, 0.0])), np.zeros(3)).homogeneous  # y axis -> z


@dataclass(frozen=True)
class WalkFrame:
    """One animation frame of a walk: sample ``sample`` of phase ``phase`` (its ``kind`` and
    ``support``), its world plate poses and leg forces (n, 6) [N] with that support."""

    phase: int
    sample: int
    kind: str
    support: str
    plates: PlateArrays
    forces: np.ndarray


@dataclass(frozen=True)
class PhaseSpan:
    """A walk phase in its animation: frames ``first..last`` (included), seconds ``start..end``."""

    phase: int
    kind: str
    support: str
    first: int
    last: int
    start: float
    end: float

    def label(self) -> str:
        return (
            f"phase {self.phase} {self.kind} ({self.support} held): frames {self.first}–{self.last}, "
            f"{self.start:.1f}–{self.end:.1f} s"
        )


def walk_frames(walk: WalkResult) -> list[WalkFrame]:
    """Every sample of every phase of a :class:`~assembler_pin.walk.WalkResult`, in order
    (the phases' plates are world poses of the original model's plates 0..n)."""
    return [
        WalkFrame(k, i, phase.kind, phase.support, plates, np.asarray(phase.forces[i], dtype=float))
        for k, phase in enumerate(walk.phases)
        for i, plates in enumerate(phase.plates)
    ]


def phase_spans(frames: Sequence[WalkFrame], fps: float) -> list[PhaseSpan]:
    """The frames and seconds of each phase with samples, frame k shown at k / ``fps`` [s]."""
    spans: list[PhaseSpan] = []
    for k, f in enumerate(frames):
        if spans and spans[-1].phase == f.phase:
            last = spans[-1]
            spans[-1] = PhaseSpan(last.phase, last.kind, last.support, last.first, k, last.start, k / fps)
        else:
            spans.append(PhaseSpan(f.phase, f.kind, f.support, k, k, k / fps, k / fps))
    return spans


def _held_node(root, foot: int, kind: str):
    return root["held"][f"{'base' if foot == 0 else 'ee'}_{kind}"]


def make_walk_markers(root, am: AssemblerModel, footholds: Sequence[pin.SE3]) -> None:
    """Under the meshcat node ``root``: a disc at every foothold (``root/footholds/<k>``, world
    frame) and one hidden held-foot disc per foot and phase kind (``root/held/<base|ee>_<kind>``,
    shown by :func:`build_walk_animation` in the frames where that foot is held)."""
    root.delete()
    radius = 1.2 * am.config.plate.node_radius
    for k, f in enumerate(footholds):
        node = root["footholds"][str(k)]
        node.set_object(mg.Cylinder(0.004, radius), material(FOOTHOLD_RGBA))
        node.set_transform(f.homogeneous @ _DISC)
    held = mg.Cylinder(0.012, 1.1 * radius)
    for foot in (0, -1):
        for kind, rgb in WALK_PHASE_RGB.items():
            node = _held_node(root, foot, kind)
            node.set_object(held, material([*rgb, 0.7]))
            node.set_property("visible", False)


#: Width and height [m] of the phase label drawn above the walk.
PHASE_LABEL_SIZE = (0.36, 0.09)


def _label_png(text: str, rgb: np.ndarray) -> bytes:
    """A PNG of ``text`` in ``rgb`` on white, 4:1 (matplotlib's Agg canvas)."""
    import io

    from matplotlib.figure import Figure

    fig = Figure(figsize=(4.0, 1.0), dpi=100)
    fig.patch.set_facecolor("white")
    fig.text(0.5, 0.5, text, ha="center", va="center", size=56, weight="bold", color=tuple(rgb))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", facecolor="white")
    return buf.getvalue()


def make_phase_labels(root, at: np.ndarray) -> None:
    """Under the meshcat node ``root``: one hidden label per phase kind (``root/labels/<kind>``),
    its name on a thin box at world point ``at`` [m] facing −y (the side camera), shown by
    :func:`build_walk_animation` in the frames of that kind."""
    w, h = PHASE_LABEL_SIZE
    for kind, rgb in WALK_PHASE_RGB.items():
        texture = mg.ImageTexture(image=mg.PngImage(_label_png(kind, rgb)))
        node = root["labels"][kind]
        node.set_object(mg.Box([w, 1e-3, h]), mg.MeshBasicMaterial(map=texture))
        T = np.eye(4)
        T[:3, 3] = at
        node.set_transform(T)
        node.set_property("visible", False)


def build_walk_animation(
    viewer, frames: Sequence[WalkFrame], fps: float, markers: str, scale: tuple[float, float] | None = None
):
    """The meshcat animation of a walk in a :class:`~assembler_pin.viz.StackViewer`: frame k
    places every body of the main stack and the payload rod at ``frames[k].plates``, shows each
    leg's force sleeve for the forces of its phase's support (sleeves by :func:`make_force_bands`)
    and the held-foot disc of each held plate in the phase's colour and the phase's name (under
    ``markers``, made by :func:`make_walk_markers` and :func:`make_phase_labels`)."""
    am = viewer.am
    anim = meshcat.animation.Animation(default_framerate=fps)
    rod = am.config.payload.offset > 0 and am.config.payload.mass > 0
    for k, f in enumerate(frames):
        with anim.at_frame(viewer.meshcat, k) as frame:
            for g, T in zip(viewer.visual_model.geometryObjects, viewer.placements(f.plates), strict=True):
                frame[viewer.viz.getViewerNodeName(g, pin.GeometryType.VISUAL)].set_transform(T)
            if rod:
                T_rod = payload_rod_transform(am, f.plates.R[-1], f.plates.p[-1])
                frame[viewer.scene_path("payload_rod")]["rod"].set_transform(T_rod)
            bottom, top = leg_vectors(am, f.plates)[:2]
            _band_frame(frame[viewer.scene_path("force_bands")], am, f.forces, bottom, top, scale)
            for foot in (0, -1):
                for kind in WALK_PHASE_RGB:
                    node = _held_node(frame[markers], foot, kind)
                    shown = kind == f.kind and foot in HELD_PLATES[f.support]
                    node.set_property("visible", "boolean", shown)
                    if shown:
                        node.set_transform(f.plates.se3(foot % (am.n + 1)).homogeneous @ _DISC)
            for kind in WALK_PHASE_RGB:
                frame[markers]["labels"][kind].set_property("visible", "boolean", kind == f.kind)
    return anim
