"""The viewer's colours: the package's one colour language (:mod:`~assembler_pin.common.palette`)
as numpy arrays, the leg force scale and meshcat materials.

Every value here is taken from :mod:`~assembler_pin.common.palette`; none is written twice.
"""

from __future__ import annotations

import meshcat.geometry as mg
import numpy as np
import numpy.typing as npt

from ..common import palette
from ..config.choices import FORCE_SCALES
from ..exceptions import AssemblerError, ViewerError

__all__ = [
    "ARM_CLUSTER_RGBA",
    "ARM_LINK_RGBA",
    "BACKGROUND_RGB",
    "CARRIER_RGBA",
    "CLOSEST_PAIR_RGBA",
    "COMPLIANCE_RGBA",
    "COMPRESSION_RGB",
    "FLOOR_RGBA",
    "FORCE_SCALE_FLOOR",
    "GHOST_RGBA",
    "LOADED_RGBA",
    "NEUTRAL_RGB",
    "OBSTACLE_RGBA",
    "PAYLOAD_RGBA",
    "PAYLOAD_ROD_RGBA",
    "TENSION_RGB",
    "VIOLATION_RGBA",
    "color_scale",
    "css",
    "force_color",
    "material",
]

COMPRESSION_RGB = np.array(palette.COMPRESSION)
"""Leg color at (or beyond) the compression limit."""
NEUTRAL_RGB = np.array(palette.NEUTRAL)
"""Leg color at zero force."""
TENSION_RGB = np.array(palette.TENSION)
"""Leg color at (or beyond) the tension limit."""
GHOST_RGBA = np.array(palette.rgba(palette.INITIAL, palette.GHOST_OPACITY))
"""Color of the translucent ghost pose (the paper draws the initial condition green)."""
LOADED_RGBA = np.array(palette.rgba(palette.LOADED, 0.45))
"""Translucent teal: the loaded pose (elastic equilibrium, displacements exaggerated)."""
COMPLIANCE_RGBA = np.array(palette.rgba(palette.COMPLIANCE, 0.55))
"""Translucent magenta: the EE's compliance ellipsoid."""
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
BACKGROUND_RGB = (np.array(palette.BACKGROUND_TOP), np.array(palette.BACKGROUND_BOTTOM))
"""Neutral background, top and bottom."""
VIOLATION_RGBA = np.array(palette.rgba(palette.VIOLATION, 0.9))
"""Yellow: the ball marking a leg that violates a limit."""

OBSTACLE_RGBA = np.array(palette.rgba(palette.OBSTACLE, palette.OBSTACLE_OPACITY))
"""Translucent stone: a scene's obstacles."""
FLOOR_RGBA = np.array(palette.rgba(palette.FLOOR, 0.5 * palette.OBSTACLE_OPACITY))
"""Translucent brown: a scene's floor plane."""
CLOSEST_PAIR_RGBA = np.array(palette.rgba(palette.CLOSEST_PAIR))
"""Cyan: the closest pair's segment and its two end balls."""


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


FORCE_SCALE_FLOOR = 0.1
"""Leg color scales: ``limit`` saturates at the force limits, ``max`` at the state's max|F|,
``auto`` (default) at the larger of max|F| and this fraction of the smaller limit."""


def color_scale(state, leg, force_scale: str = "auto") -> tuple[float, float]:
    """(tension, compression) [N] at which the leg colors of ``state`` saturate, for the leg
    limits ``leg`` (:class:`~assembler_pin.config.LegConfig`) and a scale of :data:`FORCE_SCALES`."""
    if force_scale not in FORCE_SCALES:
        raise ViewerError(f"force_scale must be one of {', '.join(FORCE_SCALES)}, got {force_scale!r}")
    if force_scale == "limit":
        return leg.max_tension, leg.max_compression
    peak = max(state.max_abs_force, 1e-9)
    if force_scale == "auto":
        peak = max(peak, FORCE_SCALE_FLOOR * min(leg.max_tension, leg.max_compression))
    return peak, peak


def material(rgba: npt.ArrayLike) -> mg.MeshPhongMaterial:
    """A meshcat material of an RGB(A) colour in [0, 1] (translucent when the opacity is < 1)."""
    rgba = np.asarray(rgba, dtype=float)
    r, g, b = (round(255 * float(c)) for c in rgba[:3])
    mat = mg.MeshPhongMaterial(color=(r << 16) + (g << 8) + b)
    if rgba.shape[0] > 3 and rgba[3] < 1.0:
        mat.transparent = True
        mat.opacity = float(rgba[3])
    return mat


def css(rgb: npt.ArrayLike) -> str:
    """CSS color of an RGB(A) triple in [0, 1] (:func:`~assembler_pin.common.palette.hex_color`)."""
    return palette.hex_color(tuple(np.asarray(rgb, dtype=float)[:3]))
