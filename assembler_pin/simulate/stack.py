"""The stack's MJCF (:mod:`assembler_pin.model.mjcf`) loaded in MuJoCo, set to our poses, and its
statics from MuJoCo's own gravity and constraint Jacobian (:func:`mujoco_statics`).

Forces are the package's: tension positive [N]; poses are world poses [m].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from ..common.naming import names
from ..exceptions import SimulationError, SingularConfigurationError
from ..kinematics import PlateArrays, leg_vectors, plate_arrays, q_from_arrays
from ..model.assembler import AssemblerModel
from ..model.mjcf import assembler_mjcf

__all__ = ["MujocoStack", "MujocoStatics", "mujoco_statics"]


def _mujoco() -> Any:
    """The ``mujoco`` module, imported on first use (SimulationError when it is not installed)."""
    try:
        import mujoco
    except ImportError as exc:  # pragma: no cover - the test extra installs it
        raise SimulationError(
            f"MuJoCo is not installed ({exc}); install it with: pip install 'assembler_pin[sim]'"
        ) from None
    return mujoco


@dataclass(frozen=True)
class MujocoStatics:
    """Statics of a pose computed by MuJoCo.

    Attributes:
        forces: (n, 6) actuator forces [N], tension positive.
        ball_forces: (n, 6, 3) force of each ball joint on its shaft, world frame [N].
        closure_residual: largest distance between the two sides of a ball joint in MuJoCo's
            model of the pose [m] (≈ 1e-15 when our q closes the loops).
    """

    forces: np.ndarray
    ball_forces: np.ndarray
    closure_residual: float

    @property
    def max_abs_force(self) -> float:
        return float(np.abs(self.forces).max())


class MujocoStack:
    """The stack's MJCF loaded in MuJoCo, with the maps between our poses and MuJoCo's state.

    ``qpos`` has the layout of the URDF's ``q`` without the root free-flyer (plate 0 is a body
    fixed to the world, placed at our plate 0's pose): per platform, the legs' ``(ux, uy,
    length)`` then the top plate's three slides and its ball quaternion, which MuJoCo orders
    ``w x y z`` and Pinocchio ``x y z w``.
    """

    def __init__(self, am: AssemblerModel) -> None:
        mujoco = _mujoco()
        self.am = am
        self.mujoco = mujoco
        self.model = mujoco.MjModel.from_xml_string(assembler_mjcf(am.config))
        self.model.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE  # efc_J as a dense matrix
        self.data = mujoco.MjData(self.model)
        body = lambda name: mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name)  # noqa: E731
        self.plate_body_ids = np.array([body(names.plate(k)) for k in range(am.n + 1)])
        self.actuated_dofs = self.model.jnt_dofadr[self.model.actuator_trnid[:, 0]]
        self.n_closure_rows = 3 * 6 * am.n

    def qpos_from_plates(self, plates: PlateArrays | Sequence | np.ndarray) -> np.ndarray:
        """MuJoCo's ``qpos`` for plate poses (closed form, loops closed to rounding)."""
        pa = plate_arrays(self.am, plates)
        _, _, vec, lengths = leg_vectors(self.am, pa)
        return self._qpos(pa, vec, lengths)

    def _qpos(self, pa: PlateArrays, vec: np.ndarray, lengths: np.ndarray) -> np.ndarray:
        q = q_from_arrays(self.am, pa, vec, lengths)[7:].reshape(self.am.n, 25).copy()
        xyzw = q[:, 21:25].copy()
        q[:, 21] = xyzw[:, 3]
        q[:, 22:25] = xyzw[:, :3]
        return q.ravel()

    def set_plates(self, plates: PlateArrays | Sequence | np.ndarray) -> PlateArrays:
        """Put MuJoCo's model at the plate poses, at rest, and run its forward pass."""
        pa = plate_arrays(self.am, plates)
        m, d = self.model, self.data
        base = pa.se3(0)
        m.body_pos[self.plate_body_ids[0]] = base.translation
        x, y, z, w = pin.Quaternion(base.rotation).coeffs()
        m.body_quat[self.plate_body_ids[0]] = [w, x, y, z]
        _, _, vec, lengths = leg_vectors(self.am, pa)
        self.mujoco.mj_resetData(m, d)
        d.qpos[:] = self._qpos(pa, vec, lengths)
        d.ctrl[:] = lengths.ravel()
        self.mujoco.mj_forward(m, d)
        return pa

    def plates(self) -> PlateArrays:
        """World poses of the plates in MuJoCo's current state."""
        ids = self.plate_body_ids
        return PlateArrays(self.data.xmat[ids].reshape(-1, 3, 3).copy(), self.data.xpos[ids].copy())

    def closure_residual(self) -> float:
        """Largest ball-joint gap [m] in the current state."""
        rows = self.data.efc_pos[: self.n_closure_rows].reshape(-1, 3)
        return float(np.linalg.norm(rows, axis=1).max())

    def actuator_forces(self) -> np.ndarray:
        """(n, 6) forces the actuators exert now [N], tension positive."""
        return -self.data.actuator_force.reshape(self.am.n, 6).copy()

    def end_stop_forces(self) -> np.ndarray:
        """(n, 6) forces the slides' end stops exert now [N], tension positive."""
        m, d = self.model, self.data
        out = np.zeros(m.nv)
        rows = np.flatnonzero(d.efc_type[: d.nefc] == self.mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT)
        if rows.size:
            J = d.efc_J[: d.nefc * m.nv].reshape(d.nefc, m.nv)[rows]
            out = J.T @ d.efc_force[rows]
        return -out[self.actuated_dofs].reshape(self.am.n, 6)


def mujoco_statics(
    am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray, stack: MujocoStack | None = None
) -> MujocoStatics:
    """Actuator forces holding a pose at rest, from MuJoCo's gravity and constraint Jacobian.

    Solves ``qfrc_bias = Bᵀ τ + efc_Jᵀ λ`` (``B`` selects the actuated slides) at zero
    velocity: 24n equations, 6n actuator and 18n ball-joint unknowns. Nothing of our
    statics is used, only MuJoCo's model of the exported MJCF.

    Raises:
        SingularConfigurationError: the pose is singular (the system has no unique solution).
    """
    stack = stack or MujocoStack(am)
    stack.set_plates(plates)
    m, d = stack.model, stack.data
    rows = stack.n_closure_rows
    J = d.efc_J[: rows * m.nv].reshape(rows, m.nv)
    A = np.zeros((m.nv, m.nu + rows))
    A[stack.actuated_dofs, np.arange(m.nu)] = 1.0
    A[:, m.nu :] = J.T
    try:
        x = np.linalg.solve(A, d.qfrc_bias)
    except np.linalg.LinAlgError:
        cond, platform = _singular_system(A, am.n, m.nu)
        raise SingularConfigurationError(
            f"MuJoCo's statics system is singular at this pose (condition number {cond:.3g}, worst: platform "
            f"{platform})",
            condition_number=cond,
            platform=platform,
        ) from None
    # efc forces act along +efc_J; the constraint's force on the shaft is its first body's row
    return MujocoStatics(
        forces=-x[: m.nu].reshape(am.n, 6),
        ball_forces=-x[m.nu :].reshape(am.n, 6, 3),
        closure_residual=stack.closure_residual(),
    )


def _singular_system(A: np.ndarray, n: int, nu: int) -> tuple[float, int]:
    """(condition number, platform) of a singular statics system ``A x = b`` of
    :func:`mujoco_statics`: the platform owning the unknown (an actuator force, 6 per
    platform, or a ball-joint force, 18 per platform) that weighs most in A's null vector."""
    s, vh = np.linalg.svd(A)[1:]
    cond = float(s[0] / s[-1]) if s[-1] > 0 else math.inf
    k = int(np.argmax(np.abs(vh[-1])))
    platform = k // 6 if k < nu else (k - nu) // 18
    return cond, min(platform, n - 1)
