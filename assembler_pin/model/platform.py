"""One Pinocchio model per platform: the statics of a stack of any size in linear time and memory.

A whole-stack Pinocchio model has nv = 24n + 6 velocity coordinates, and its ``Data``
holds dense nv × nv matrices and nv³ derivative buffers (0.6 GB at n = 8). The statics of
platform j depend only on its own pose and the load from above, so each platform is
computed on a small model of its own — its bottom plate (free-flyer root), its six legs
(universal joint + prismatic actuator, motor and shaft) and its top plate, plus the payload
on the last platform — loaded from the 1-platform URDF the package generates
(:func:`~assembler_pin.model.urdf.assembler_urdf`), nv = 30.

Every platform of a stack is the same platform turned about z: platform j's nodes sit at
90° + 60°·j + 120°·m in both of its plates' frames, so in plate frames turned by
``Rz(60°·j)`` it is platform 0. Two models serve any n: one for the inner platforms and
one for the last (with the payload); each owns its ``Data``.

The stack is solved from the top down: platform j's model gets the weight of everything
above its top plate as an external force on the top plate's joint
(``pin.computeStaticTorque`` with ``fext``), and the weight of everything above its
bottom plate follows from its root rows. Units: SI; frames as in the README.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..common.naming import names
from ..config.schema import AssemblerConfig, PayloadConfig
from .geometry import LEGS_PER_PLATFORM, leg_geometry
from .urdf import assembler_urdf

__all__ = ["PLATFORM_TURN", "PlatformModel", "PlatformStatics", "StackPlan", "platform_turns", "stack_gravity_terms"]

#: The turn about z between consecutive platforms' geometry [rad].
PLATFORM_TURN = math.radians(60.0)


def platform_turns(n: int) -> np.ndarray:
    """(n, 3, 3): ``Rz(60°·j)``, the turn that maps platform j's plate frames onto platform 0's."""
    a = PLATFORM_TURN * np.arange(n)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((n, 3, 3))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1], out[:, 2, 2] = c, -s, s, c, 1.0
    return out


class PlatformModel:
    """The Pinocchio model of one platform (platform 0's geometry) and its own ``Data``.

    Attributes:
        model, data: Pinocchio model (free-flyer root = bottom plate; 6 legs × (ux, uy,
            actuator); free-flyer top plate) and its data, written only by this object.
        leg_idx_q, leg_idx_v: (6, 3) q / v indices of each leg's (ux, uy, actuator).
        top_joint: joint id of the top plate; top_rows_v: its 6 v indices.
        rest_offset: (3,) the top plate joint's home placement (a translation) [m].
        leg_base_rotation: (6, 3, 3) bottom-plate frame → universal-joint frame.
        root_mass [kg], root_com (3,) [m]: the bottom plate body (mass and CoM in its frame).
    """

    def __init__(self, config: AssemblerConfig, payload: PayloadConfig) -> None:
        cfg = config.replace(platforms=1, payload=payload)
        self.model = pin.buildModelFromXML(assembler_urdf(cfg), pin.JointModelFreeFlyer())
        self.model.gravity.linear = np.array([0.0, 0.0, -config.gravity])
        self.data = self.model.createData()
        model = self.model
        parts = ("ux", "uy", "actuator")
        ids = np.array([[model.getJointId(names.leg(0, i, p)) for p in parts] for i in range(LEGS_PER_PLATFORM)])
        self.leg_idx_q = np.vectorize(lambda k: model.idx_qs[int(k)])(ids)
        self.leg_idx_v = np.vectorize(lambda k: model.idx_vs[int(k)])(ids)
        self.top_joint = model.getJointId(names.plate_joint(0))
        self.top_idx_q = model.idx_qs[self.top_joint]
        self.top_rows_v = model.idx_vs[self.top_joint] + np.arange(6)
        self.rest_offset = model.jointPlacements[self.top_joint].translation.copy()
        self.leg_base_rotation = leg_geometry(cfg).leg_base_rotation[0]
        # the layout the statics slice by: root free-flyer, legs 0..5 (ux, uy, actuator), top plate
        if not (np.array_equal(self.leg_idx_v, 6 + np.arange(18).reshape(6, 3)) and self.top_rows_v[0] == 24):
            raise ValueError("platform model: unexpected joint order")  # the generator's own layout
        self.root_mass = float(model.inertias[1].mass)
        self.root_com = model.inertias[1].lever.copy()
        self.fext = pin.StdVec_Force()
        for _ in range(model.njoints):
            self.fext.append(pin.Force.Zero())

    def static_terms(self, q: np.ndarray, load_on_top: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``g(q) - Jᵀ f_ext`` with ``load_on_top`` (a force [f, m] in the top plate's frame, about
        its origin) on the top plate, and the world-frame joint Jacobians ``data.J`` at q.

        Runs ``pin.computeStaticTorque`` and ``pin.computeJointJacobians`` on this object's data.
        """
        self.fext[self.top_joint] = pin.Force(load_on_top)
        tau = pin.computeStaticTorque(self.model, self.data, q, self.fext)
        pin.computeJointJacobians(self.model, self.data, q)
        return tau, self.data.J


@dataclass(frozen=True)
class PlatformStatics:
    """The Pinocchio terms the statics of a stack need, per platform (see :func:`stack_gravity_terms`).

    Attributes:
        g_legs: (n, 6, 3) generalized gravity of each leg's (ux, uy, actuator) [N·m, N·m, N].
        g_top: (n, 6) top plate's free-flyer rows ``g - Jᵀ f_ext`` (the weight of the top plate
            and everything above it), in the top plate's own frame [N, N·m].
        leg_columns: (n, 6, 3, 6) world-frame joint Jacobian columns of each leg's joints.
        top_columns: (n, 6, 6) world-frame Jacobian columns of each top plate's free-flyer
            (twists in the top plate's own frame, as the whole-stack model's free-flyer).
        base_wrench_local: (6,) root rows of platform 0: the wrench the base mount supplies,
            in plate 0's frame [N, N·m].
    """

    g_legs: np.ndarray
    g_top: np.ndarray
    leg_columns: np.ndarray
    top_columns: np.ndarray
    base_wrench_local: np.ndarray


def _block_turns(turns: np.ndarray) -> np.ndarray:
    """(m, 6, 6) ``diag(R, R)`` of (m, 3, 3) rotations: turns a wrench or twist ``[v; w]``."""
    out = np.zeros((turns.shape[0], 6, 6))
    out[:, :3, :3] = turns
    out[:, 3:, 3:] = turns
    return out


class StackPlan:
    """The constants of :func:`stack_gravity_terms` for a stack of n platforms (built once per model).

    Attributes:
        inner, last: the platform models.
        turns: (n, 3, 3) ``Rz(60°·j)``; blocks: (n, 6, 6) ``diag(turn, turn)``.
        to_lower: (6, 6) turns a wrench from platform j's turned frame into platform j-1's.
        own_map: (3, 6) a bottom plate's weight wrench (about its origin, turned frame) per unit
            "down" direction in that frame, times g [N, N·m].
    """

    def __init__(self, inner: PlatformModel, last: PlatformModel, n: int) -> None:
        self.inner, self.last, self.n = inner, last, n
        self.turns = platform_turns(n)
        self.blocks = _block_turns(self.turns)
        self.blocks_t = self.blocks.transpose(0, 2, 1).copy()
        self.to_lower = _block_turns(platform_turns(2)[1:])[0] if n > 1 else np.eye(6)
        g = float(-inner.model.gravity.linear[2])
        skew_com = pin.skew(inner.root_com)
        self.own_map = inner.root_mass * g * np.hstack([np.eye(3), skew_com.T])


def stack_gravity_terms(plan: StackPlan, R: np.ndarray, q_platforms: np.ndarray) -> PlatformStatics:
    """Generalized gravity and Jacobians of every platform, from the top down.

    Args:
        plan: the stack's constants (models, turns).
        R: (n+1, 3, 3) world orientations of the plates.
        q_platforms: (n, nq) each platform model's configuration (frames turned by ``Rz(60°·j)``).

    Returns:
        A :class:`PlatformStatics`, with ``g_top`` and ``top_columns`` turned back into each
        top plate's own frame.
    """
    n = q_platforms.shape[0]
    inner, last = plan.inner, plan.last
    # each bottom plate's own weight as a wrench in its turned frame (about its origin): the
    # root rows support that plate and everything above it. "Down" in the turned frame is
    # -(third row of R_j·turn_j).
    down = -np.einsum("ja,jab->jb", R[:-1, 2, :], plan.turns)
    own = down @ plan.own_map
    tau_rows = np.empty((n, 6, 3))
    top_rows = np.empty((n, 6))
    leg_columns = np.empty((n, 6, 3, 6))
    top_columns = np.empty((n, 6, 6))
    load = np.zeros(6)  # weight of everything above plate j+1, in its turned frame
    root = np.zeros(6)
    for j in range(n - 1, -1, -1):
        model = last if j == n - 1 else inner
        tau, J = model.static_terms(q_platforms[j], load)
        tau_rows[j] = tau[6:24].reshape(6, 3)  # the legs' (ux, uy, actuator) rows
        top_rows[j] = tau[24:30]
        leg_columns[j] = J[:, 6:24].T.reshape(6, 3, 6)
        top_columns[j] = J[:, 24:30]
        root = tau[:6]
        load = plan.to_lower @ (-root - own[j])
    g_top = np.matmul(plan.blocks, top_rows[..., None])[..., 0]
    top_columns = np.matmul(top_columns, plan.blocks_t)  # twists in the plate's own axes
    return PlatformStatics(tau_rows, g_top, leg_columns, top_columns, root)
