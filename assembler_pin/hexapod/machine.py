"""The hexapod machine: k stacks (each the model ``am``, its own n) whose base plates are the
feet and whose EE plates are fixed to one rigid body.

* :func:`ring_stacks` — k stacks at their home poses, feet on a circle of given radius on the
  floor ``z = 0``, each turned to face outwards.
* :func:`checked_stacks`, :func:`checked_body` — the strict readers of the API's arguments.
* :func:`machine_com` — the whole machine's mass and centre of mass (body, every plate, motor,
  shaft and tool payload) at given plate poses.

Frames and units: world frame, z up, metres, kilograms; a stack is its n+1 plate poses,
plate 0 (the foot) first.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.validation import as_float_array
from ..config.bounds import BOUNDS, check_bound
from ..exceptions import HexapodError
from ..kinematics import PlateArrays, leg_vectors, plate_arrays
from ..model.assembler import AssemblerModel, checked_model

__all__ = ["MAX_STACKS", "checked_body", "checked_stacks", "configured_hexapod", "machine_com", "ring_stacks"]

#: Most stacks under one body.
MAX_STACKS = 16


def ring_stacks(am: AssemblerModel, count: int, radius: float) -> list[PlateArrays]:
    """``count`` stacks at the model's home poses, foot ``i`` at angle ``2π i / count`` on the
    circle of ``radius`` [m] about the world z axis (floor ``z = 0``), its x axis outwards.

    Raises:
        HexapodError: ``count`` outside 1..:data:`MAX_STACKS` or ``radius`` outside
            ``hexapod.radius``.
    """
    checked_model(am)
    check_bound("hexapod.stacks", count, "stacks", HexapodError)
    check_bound("hexapod.radius", radius, "radius", HexapodError)
    out = []
    for a in np.arange(int(count)) * 2.0 * np.pi / int(count):
        foot = pin.SE3(pin.exp3(np.array([0.0, 0.0, a])), np.array([radius * np.cos(a), radius * np.sin(a), 0.0]))
        out.append(PlateArrays.from_se3([foot * m for m in am.home]))
    return out


def configured_hexapod(am: AssemblerModel) -> tuple[list[PlateArrays], float, np.ndarray]:
    """The stacks, body mass [kg] and body centre of mass (world, [m]) of the model's
    configuration's ``hexapod`` section: :func:`ring_stacks` of ``stacks`` at ``radius``, the
    body's centre of mass ``body_com`` from the centre of the EE plates' circle."""
    hc = am.config.hexapod
    stacks = ring_stacks(am, hc.stacks, hc.radius)
    centre = np.mean([s.p[-1] for s in stacks], axis=0)
    return stacks, hc.body_mass, centre + np.asarray(hc.body_com, float)


def checked_stacks(am: AssemblerModel, stacks: Sequence) -> list[PlateArrays]:
    """Each stack's plate poses validated (:func:`~assembler_pin.kinematics.plate_arrays`).

    Raises:
        HexapodError: not a list of 1..:data:`MAX_STACKS` stacks, or a model of more
            platforms than ``hexapod.platforms`` allows.
        PoseError: a malformed stack.
    """
    checked_model(am)
    check_bound("hexapod.platforms", am.n, "a hexapod stack's platforms (the model's)", HexapodError)
    if isinstance(stacks, (str, bytes)) or not hasattr(stacks, "__len__") or not 1 <= len(stacks) <= MAX_STACKS:
        raise HexapodError(f"stacks must be a list of 1..{MAX_STACKS} stacks, each its n+1 world plate poses")
    out = [plate_arrays(am, s) for s in stacks]
    for i, pa in enumerate(out):
        leg_vectors(am, pa)  # refuses a leg whose two joint centres coincide
        if not np.isfinite(pa.p).all():
            raise HexapodError(f"stack {i}: plate positions must be finite")
    return out


def checked_body(body_mass: object, body_com: npt.ArrayLike) -> tuple[float, np.ndarray]:
    """``body_mass`` [kg] within ``hexapod.body_mass`` and ``body_com`` three finite numbers [m]
    within ``pose.translation``.

    Raises:
        HexapodError: either is not.
    """
    check_bound("hexapod.body_mass", body_mass, "body_mass", HexapodError)
    com = as_float_array(body_com, "body_com (three numbers x, y, z [m])", (3,), error=HexapodError)
    high = BOUNDS["pose.translation"].high
    if not (np.isfinite(com).all() and np.abs(com).max() <= high):
        raise HexapodError(f"body_com: three finite numbers within ±{high:g} m, got {com.tolist()}")
    return float(body_mass), com  # type: ignore[arg-type]


def machine_com(am: AssemblerModel, R: np.ndarray, p: np.ndarray, body_mass: float, body_com: np.ndarray):
    """The whole machine's mass [kg] and centre of mass (3,) [m] at plates ``R`` (k, n+1, 3, 3),
    ``p`` (k, n+1, 3): the body, every plate (at its origin), every motor (``motor_com`` above
    its bottom joint on the leg axis) and shaft (``shaft_com`` below its top joint) and each
    stack's tool payload (``payload.offset`` along its EE plate's z)."""
    cfg = am.config
    leg = cfg.leg
    masses, moments = [body_mass], [body_mass * body_com]
    for Ri, pi in zip(R, p, strict=True):
        bottom, top, vec, lengths = leg_vectors(am, PlateArrays(Ri, pi))
        u = vec / lengths[..., None]
        motors = bottom + leg.motor_com * u
        shafts = top - leg.shaft_com * u
        payload = pi[-1] + cfg.payload.offset * Ri[-1][:, 2]
        count = motors.shape[0] * motors.shape[1]
        masses += [cfg.plate.mass * len(pi), leg.motor_mass * count, leg.shaft_mass * count, cfg.payload.mass]
        moments += [
            cfg.plate.mass * pi.sum(axis=0),
            leg.motor_mass * motors.sum(axis=(0, 1)),
            leg.shaft_mass * shafts.sum(axis=(0, 1)),
            cfg.payload.mass * payload,
        ]
    total = float(sum(masses))
    return total, np.sum(moments, axis=0) / total if total > 0 else np.asarray(body_com, float)
