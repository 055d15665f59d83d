"""The carrier arm: a serial robot from example-robot-data holding the stack's base plate.

* :data:`CARRIERS` — the supported arms (:class:`CarrierSpec`).
* :class:`Carrier` — the carrier's Pinocchio model (its own ``Data``, of which it is the only
  writer), the visual model with its meshes, the mount, forward kinematics and a joint-limited
  inverse kinematics of the base plate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..config.bounds import check_bound
from ..config.choices import CARRIER_NAMES, check_names
from ..exceptions import AssemblerError, OptionsError, PoseError, UnknownCarrierError
from ..kinematics import to_se3

__all__ = ["CARRIERS", "Carrier", "CarrierSpec", "IKResult", "robots_directory"]


@dataclass(frozen=True)
class CarrierSpec:
    """A supported carrier.

    Attributes:
        urdf: path of its URDF under example-robot-data's ``robots`` directory.
        tool_frame: the frame the stack's base plate is mounted on.
        locked: joints held at zero (a gripper's fingers).
        upright_q: a joint configuration with the tool frame's z axis near world +z [rad]
            (the default, so the stack stands upright above the tool).
        description: what it is, and its rated payload where the maker gives one.
    """

    urdf: str
    tool_frame: str
    locked: tuple[str, ...] = ()
    upright_q: tuple[float, ...] = ()
    description: str = ""


CARRIERS: dict[str, CarrierSpec] = {
    "ur3": CarrierSpec(
        "ur_description/urdf/ur3_robot.urdf",
        "tool0",
        (),
        (-0.041, -0.693, 1.127, 1.138, -1.571, 1.612),
        "Universal Robots UR3, 6 joints (rated payload 3 kg)",
    ),
    "ur5": CarrierSpec(
        "ur_description/urdf/ur5_robot.urdf",
        "tool0",
        (),
        (-0.02, -1.127, 1.535, 1.164, -1.571, 1.591),
        "Universal Robots UR5, 6 joints (rated payload 5 kg)",
    ),
    "ur10": CarrierSpec(
        "ur_description/urdf/ur10_robot.urdf",
        "tool0",
        (),
        (-0.023, -1.205, 1.738, 1.038, -1.571, 1.594),
        "Universal Robots UR10, 6 joints (rated payload 10 kg)",
    ),
    "panda": CarrierSpec(
        "panda_description/urdf/panda.urdf",
        "panda_link8",
        ("panda_finger_joint1", "panda_finger_joint2"),
        (-1.003, -0.35, 1.067, -2.689, -2.649, 0.688, 0.356),
        "Franka Emika Panda, 7 joints, fingers locked (rated payload 3 kg)",
    ),
}
"""The supported carriers by name (see :class:`CarrierSpec`)."""
check_names(CARRIERS, CARRIER_NAMES, "carriers")


@cache
def robots_directory() -> Path:
    """example-robot-data's ``robots`` directory (URDFs and meshes).

    Raises:
        AssemblerError: the package is not installed (``pip install example-robot-data``).
    """
    from importlib import metadata

    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        raise AssemblerError(
            "carriers need example-robot-data: pip install 'assembler_pin[carrier]' (or example-robot-data)"
        ) from None
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    if not path.is_dir():
        raise AssemblerError(f"example-robot-data is installed but has no robots directory at {path}")
    return path


@dataclass(frozen=True)
class IKResult:
    """Joint-limited inverse kinematics of the base plate (:meth:`Carrier.ik`).

    Attributes:
        q: joint angles [rad] (the last iterate when it failed), within the joint limits.
        success: the base plate reaches the target within ``tolerance``.
        error: norm of the SE(3) log of the remaining error (m and rad mixed).
        iterations: iterations used.
    """

    q: np.ndarray
    success: bool
    error: float
    iterations: int


class Carrier:
    """A serial arm from example-robot-data with the stack's base plate on its tool frame.

    Args:
        name: one of :data:`CARRIERS`.
        mount: pose of the base plate in the tool frame (default identity: the plate's
            centre on the flange, its z axis along the tool's z).

    Attributes:
        name, spec: the carrier and its :class:`CarrierSpec`.
        model, data: its Pinocchio model (fingers locked) and data; this object is the
            only writer of ``data`` (``framesForwardKinematics``, ``computeStaticTorque``,
            ``computeFrameJacobian``).
        visual_model: its visual geometry (meshes from example-robot-data).
        base_frame: id of the frame ``assembler_base`` added at the mount (the base plate).
        effort_limit: (nv,) the URDF's joint effort limits [N·m].
    """

    def __init__(self, name: str, mount: pin.SE3 | npt.ArrayLike | None = None) -> None:
        key = str(name).lower()
        if key not in CARRIERS:
            raise UnknownCarrierError(f"unknown carrier {name!r}; supported: {', '.join(CARRIERS)}")
        self.name, self.spec = key, CARRIERS[key]
        self.mount = pin.SE3.Identity() if mount is None else to_se3(mount, "mount")
        robots = robots_directory()
        urdf = str(robots / self.spec.urdf)
        full = pin.buildModelFromUrdf(urdf)
        visual = pin.buildGeomFromUrdf(full, urdf, pin.GeometryType.VISUAL, package_dirs=[str(robots.parent.parent)])
        locked = [full.getJointId(j) for j in self.spec.locked]
        if locked:
            self.model, self.visual_model = pin.buildReducedModel(full, visual, locked, pin.neutral(full))
        else:
            self.model, self.visual_model = full, visual
        tool = self.model.getFrameId(self.spec.tool_frame)
        frame = self.model.frames[tool]
        self.base_frame = self.model.addFrame(
            pin.Frame("assembler_base", frame.parentJoint, tool, frame.placement * self.mount, pin.FrameType.OP_FRAME)
        )
        self.data = self.model.createData()
        self.effort_limit = np.asarray(self.model.effortLimit, dtype=float).copy()
        self.lower = np.asarray(self.model.lowerPositionLimit, dtype=float).copy()
        self.upper = np.asarray(self.model.upperPositionLimit, dtype=float).copy()

    def __repr__(self) -> str:
        return (
            f"Carrier({self.name!r}, {self.model.nv} joints, tool frame {self.spec.tool_frame!r}, effort limits "
            f"{np.round(self.effort_limit, 1).tolist()} N·m)"
        )

    @property
    def upright_q(self) -> np.ndarray:
        """The spec's upright configuration [rad]."""
        return np.array(self.spec.upright_q, dtype=float)

    def check_q(self, q: npt.ArrayLike, what: str = "carrier q") -> np.ndarray:
        """``q`` as an (nv,) array within the joint limits, or a :class:`PoseError`."""
        raw = np.asarray(q)
        if raw.dtype.kind not in "iuf":  # no strings, booleans or objects
            raise PoseError(f"{what} must be {self.model.nq} joint angles [rad] (numbers), got {raw.dtype} values")
        arr = raw.astype(float).ravel()
        if arr.shape != (self.model.nq,) or not np.all(np.isfinite(arr)):
            raise PoseError(f"{what} must be {self.model.nq} finite joint angles [rad] for {self.name}, got {arr}")
        outside = np.flatnonzero((arr < self.lower - 1e-9) | (arr > self.upper + 1e-9))
        if outside.size:
            k = int(outside[0])
            raise PoseError(
                f"{what}: joint {k} = {arr[k]:.4f} rad is outside [{self.lower[k]:.4f}, {self.upper[k]:.4f}]"
            )
        return arr

    def base_pose(self, q: npt.ArrayLike) -> pin.SE3:
        """World pose of the stack's base plate at joint angles ``q``."""
        pin.framesForwardKinematics(self.model, self.data, self.check_q(q))
        return self.data.oMf[self.base_frame].copy()

    def joint_points(self, q: npt.ArrayLike) -> np.ndarray:
        """(njoints, 3) world positions of the joints and the base frame [m] (for framing a view)."""
        pin.framesForwardKinematics(self.model, self.data, self.check_q(q))
        pts = [self.data.oMi[k].translation for k in range(self.model.njoints)]
        return np.array([*pts, self.data.oMf[self.base_frame].translation])

    def ik(self, target: pin.SE3, q0: npt.ArrayLike, tolerance: float = 1e-9, max_iterations: int = 200) -> IKResult:
        """Joint angles placing the base plate at ``target``, from ``q0``: damped least
        squares on the SE(3) log error (``Jlog6`` of the frame Jacobian), clipped to the
        joint limits at every step."""
        check_bound("carrier.ik_iterations", max_iterations, "max_iterations", OptionsError)
        q = np.clip(self.check_q(q0, "q0"), self.lower, self.upper)
        damping = 1e-6
        err = math.inf
        for it in range(1, max_iterations + 1):
            pin.framesForwardKinematics(self.model, self.data, q)
            current = self.data.oMf[self.base_frame]
            e = pin.log6(current.actInv(target)).vector
            err = float(np.linalg.norm(e))
            if err < tolerance:
                return IKResult(q, True, err, it)
            J = pin.Jlog6(current.actInv(target)) @ pin.computeFrameJacobian(
                self.model, self.data, q, self.base_frame, pin.ReferenceFrame.LOCAL
            )
            dq = J.T @ np.linalg.solve(J @ J.T + damping * np.eye(6), e)
            q = np.clip(pin.integrate(self.model, q, dq), self.lower, self.upper)
        return IKResult(q, False, err, max_iterations)
