"""Motions for the viewer: states interpolated in leg-length space, and the animated force sleeves.

meshcat animates transforms and visibility but not material colours, so a leg's force colour
in an animation is a sleeve of its force level's colour around its middle: one hidden sleeve
per leg and level (:func:`make_force_bands`), the one of the frame's level shown
(:func:`force_band_frame`). World frame O, metres, newtons.
"""

from __future__ import annotations

from collections.abc import Sequence

import meshcat.animation
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin

from ..exceptions import AssemblerError, ConvergenceError
from ..geometry import DIMENSIONS
from ..kinematics import PlateArrays, leg_state, stack_forward_kinematics
from ..model import AssemblerModel
from ..naming import names
from ..state import StackState, evaluate_state
from .camera import cylinder_between
from .colors import force_color, material
from .drawing import payload_rod_transform
from .placements import as_plates

__all__ = [
    "FORCE_BAND_LENGTH",
    "FORCE_BAND_LEVELS",
    "build_animation",
    "force_band_frame",
    "interpolate_states",
    "make_force_bands",
]

FORCE_BAND_LEVELS = np.linspace(-1.0, 1.0, 11)
"""Force levels (fraction of the compression / tension limit) of an animation's leg sleeves."""
FORCE_BAND_LENGTH = 0.08
"""Length of an animated leg's force sleeve [m]."""


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


def build_animation(viewer, states: Sequence[StackState | PlateArrays], fps: float, color_forces: bool):
    """The meshcat animation of ``states`` in a :class:`~assembler_pin.viz.StackViewer`: frame k
    moves every body of its main stack and the payload rod to ``states[k]`` and, with
    ``color_forces``, shows each leg's force sleeve (built by :func:`make_force_bands`)."""
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
                force_band_frame(frame[viewer.scene_path("force_bands")], am, state)
    return anim


def make_force_bands(root, am: AssemblerModel) -> None:
    """One hidden sleeve per leg and force level under the meshcat node ``root``, at
    ``root/<leg name>/level<k>`` (:func:`force_band_frame` shows one per frame)."""
    root.delete()
    leg = am.config.leg
    levels = FORCE_BAND_LEVELS
    forces = np.where(levels >= 0, levels * leg.max_tension, levels * leg.max_compression)
    colors = force_color(forces, leg.max_tension, leg.max_compression)
    shape = mg.Cylinder(FORCE_BAND_LENGTH, 1.3 * DIMENSIONS.motor_radius)
    for j in range(am.n):
        for i in range(6):
            for k, rgb in enumerate(colors):
                node = root[names.leg(j, i)][f"level{k}"]
                node.set_object(shape, material([*rgb, 1.0]))
                node.set_property("visible", False)


def force_band_frame(root, am: AssemblerModel, state: StackState) -> None:
    """In one animation frame (``root`` its node of the sleeves), place and show the sleeve
    of each leg's force level and hide the others."""
    leg = am.config.leg
    fraction = np.where(state.forces >= 0, state.forces / leg.max_tension, state.forces / leg.max_compression)
    level = np.abs(FORCE_BAND_LEVELS[None, None, :] - np.clip(fraction, -1, 1)[..., None]).argmin(axis=-1)
    for j in range(am.n):
        for i in range(6):
            T = cylinder_between(state.legs.bottom_points[j, i], state.legs.top_points[j, i])
            for k in range(len(FORCE_BAND_LEVELS)):
                node = root[names.leg(j, i)][f"level{k}"]
                node.set_property("visible", "boolean", bool(k == level[j, i]))
                if k == level[j, i]:
                    node.set_transform(T)
