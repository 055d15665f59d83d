"""Meshcat viewing of the stack: poses, leg forces, helper arm, ghosts, animations, the
loaded pose and the EE's compliance ellipsoid.

:class:`StackViewer` draws the stack with :class:`pinocchio.visualize.MeshcatVisualizer`
and a visual geometry model parsed from the generated URDF (primitive shapes only). One
concern per module:

* :mod:`.colors` — the package's colour language (:mod:`~assembler_pin.common.palette`) as arrays,
  the leg force scale (:func:`force_color`: blue compression ↔ gray zero ↔ red tension);
* :mod:`.camera` — :func:`camera_for_points`, the one frame-along-an-axis helper;
* :mod:`.placements` — where each visual goes (Pinocchio's kinematics or the closed form);
* :mod:`.drawing` — helper arm, violation marks, payload rod, one-colour meshes;
* :mod:`.overlay` — the page's title, legend and colour bar (HTML/CSS);
* :mod:`.animation` — :func:`interpolate_states`, force sleeves, meshcat animations;
* :mod:`.compliance` — the loaded pose (exaggerated) and the compliance ellipsoid;
* :mod:`.obstacles` — a scene's obstacles and floor, the closest pair of bodies marked;
* :mod:`.scene` — :class:`StackScene`: the server, the main stack, animations, the page;
* :mod:`.viewer` — :class:`StackViewer`: a scene that also draws beside the stack;
* :mod:`.server` — the meshcat server process: its page listens on 127.0.0.1 unless another
  ``host`` is asked for, and it stops when the Python process that started it ends, by any
  signal.

Everything is in the world frame O (z up) and SI units.
"""

from __future__ import annotations

from ..common.signals import StopRequested, interrupt_on_signals
from .animation import FORCE_BAND_LENGTH, FORCE_BAND_LEVELS, interpolate_states
from .camera import CAMERA_FOV_DEG, Camera, camera_for_points, frame_along_axis
from .colors import (
    ARM_CLUSTER_RGBA,
    ARM_LINK_RGBA,
    BACKGROUND_RGB,
    CARRIER_RGBA,
    COMPLIANCE_RGBA,
    COMPRESSION_RGB,
    FORCE_SCALE_FLOOR,
    GHOST_RGBA,
    LOADED_RGBA,
    NEUTRAL_RGB,
    PAYLOAD_RGBA,
    PAYLOAD_ROD_RGBA,
    TENSION_RGB,
    VIOLATION_RGBA,
    force_color,
)
from .compliance import (
    EllipsoidView,
    LoadedView,
    auto_exaggeration,
    compliance_ellipsoid,
    ellipsoid_view,
    exaggerated_plates,
    loaded_view,
)
from .scene import StackScene
from .server import DEFAULT_HOST, ServerProcess, start_server
from .viewer import StackViewer

__all__ = [
    "ARM_CLUSTER_RGBA",
    "ARM_LINK_RGBA",
    "BACKGROUND_RGB",
    "CAMERA_FOV_DEG",
    "CARRIER_RGBA",
    "COMPLIANCE_RGBA",
    "COMPRESSION_RGB",
    "DEFAULT_HOST",
    "FORCE_BAND_LENGTH",
    "FORCE_BAND_LEVELS",
    "FORCE_SCALE_FLOOR",
    "GHOST_RGBA",
    "LOADED_RGBA",
    "NEUTRAL_RGB",
    "PAYLOAD_RGBA",
    "PAYLOAD_ROD_RGBA",
    "TENSION_RGB",
    "VIOLATION_RGBA",
    "Camera",
    "EllipsoidView",
    "LoadedView",
    "ServerProcess",
    "StackScene",
    "StackViewer",
    "StopRequested",
    "auto_exaggeration",
    "camera_for_points",
    "compliance_ellipsoid",
    "ellipsoid_view",
    "exaggerated_plates",
    "force_color",
    "frame_along_axis",
    "interpolate_states",
    "interrupt_on_signals",
    "loaded_view",
    "start_server",
]
