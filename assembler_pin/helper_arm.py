"""The helper arm: a fast, valid initial pose of the whole stack for a goal (paper §III).

The helper arm is a second, ordinary serial model (generated URDF, loaded into Pinocchio
with ``pin.buildModelFromXML``) that stands in for the stack:

* **Geometry.** A 3n-DOF arm: n *clusters* of three co-located revolute joints about
  the local x, y and z axes (in that order from the base, so a cluster rotates by
  ``Rx(a)·Ry(b)·Rz(c)``). The chain is::

      plate_0 (base) → d/2 → cluster 0 → d → cluster 1 → … → cluster n-1 → d/2 → plate_n (tip)

  with every link along the local +z axis. Cluster j (URDF joints ``sp{j}_rx``,
  ``sp{j}_ry``, ``sp{j}_rz``; the paper's cluster j+1) sits at the mid-height point of
  Stewart platform j. The fixed links ``plate_k`` (k = 1..n-1) are the midpoints of the
  links between clusters k-1 and k, with that link's orientation — "the plates at the
  midpoints between the arm joints" of the paper. So SP j's relative pose is
  ``T(d/2) · R_cluster_j · T(d/2)``: a tilt/twist of the top plate about the platform's
  mid-height point, which is the motion that spreads the stroke most evenly over the
  six legs. ``plate_n``, the tip, is the end effector. ``d`` starts at the home SP
  height ``d0 = cfg.home_height`` (at ``q = 0`` the arm *is* the home pose).

* **Joint limits** come from what one SP can do about its mid-height point at height
  ``d`` (:func:`cluster_limits`): the x and y joints get the largest tilt ``θ`` such
  that ``T(d/2)·exp3(θ·a)·T(d/2)`` keeps every leg of every platform within
  ``[min_length, max_length]``, both joint deflections ``<= max_deflection`` and the
  top joints above the bottom joints — the minimum over 24 horizontal axes ``a``
  (every 15°), found by bisection to 1e-10 rad. The z joint gets the same for a twist
  about z (minimum of both signs). A box of such limits does not guarantee a valid
  stack (a tilt about x and y at once is larger than either), so every arm solution is
  checked on the real stack afterwards.

* **IK** (:meth:`HelperArm.ik`): ``scipy.optimize.least_squares`` (``trf``, bounds = the
  joint limits) on the 6D error ``log6(goal⁻¹ · tip(q))`` with its analytic Jacobian
  ``Jlog6 · J_tip`` (Pinocchio LOCAL frame Jacobian), plus two more residual blocks:
  the stack's own leg constraints (stroke, deflection, continuous translation) of the
  plates the arm would place, as a hinge penalty (:meth:`HelperArm.stack_violation`,
  forward-difference Jacobian) — the box limits alone let combined x/y tilts break
  legs — and a pull ``w·q`` toward zero so that the bending is spread evenly over the
  clusters (the paper's "minimize angular deviation"). A second solve without the pull
  then drives the goal error to machine precision. Optional deterministic restarts
  (``HelperArmOptions.restarts``, default none: they did not raise the success rate).

* **Initial condition** (:func:`initial_condition`): IK at ``d0``; when the arm does not
  reach the goal, or reaches it with plates that break a kinematic constraint of the
  stack, the arm is rebuilt with ``d = d0 + s, d0 - s, d0 + 2s, …`` (``s`` the user step)
  until ``max_attempts`` arm solves (the paper's recursion limit), skipping ``d`` where a
  level SP cannot stand (:func:`height_range`). On success plate n is put exactly at
  the goal and the leg lengths follow from the SP IK
  (:func:`~assembler_pin.kinematics.leg_state`). On failure the home pose is returned
  with ``success=False`` and the reason. Unreachable goals are answers, never
  exceptions; malformed goals raise :class:`~assembler_pin.exceptions.PoseError`.

Frames: the arm's base is plate 0's world pose (``am.home[0]``, identity by default);
all poses returned are world poses. Units: metres and radians.
"""

from __future__ import annotations

import functools
import logging
import math
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pinocchio as pin
from scipy.optimize import least_squares

from .config import AssemblerConfig
from .constraints import GoalTolerance, evaluate_constraints
from .geometry import LegGeometry, leg_geometry
from .kinematics import PlateArrays, leg_state, to_se3
from .model import AssemblerModel
from .state import StackState, evaluate_state

__all__ = [
    "HELPER_ARM_URDF_FILENAME",
    "KINEMATIC_VIOLATIONS",
    "ArmIKResult",
    "HelperArm",
    "HelperArmOptions",
    "InitialConditionResult",
    "cluster_limits",
    "height_range",
    "helper_arm_urdf",
    "initial_condition",
]

logger = logging.getLogger(__name__)

HELPER_ARM_URDF_FILENAME = "helper_arm.urdf"

#: Violation kinds that make an initial condition invalid (force limits are reported only).
KINEMATIC_VIOLATIONS = frozenset(
    {
        "min_length",
        "max_length",
        "deflection_bottom",
        "deflection_top",
        "continuous_translation",
        "ee_position",
        "ee_rotation",
        "singular",
    }
)

_AXIS_COUNT = 24  # horizontal tilt axes tried by cluster_limits (every 15 degrees)
_BISECTION_TOL = 1e-10  # [rad] and [m]


# ---------------------------------------------------------------------- SP validity
@functools.lru_cache(maxsize=64)
def _geometry(cfg: AssemblerConfig) -> LegGeometry:
    return leg_geometry(cfg)


def _rotations(rotvecs: np.ndarray) -> np.ndarray:
    """exp3 of each row of (m, 3) rotation vectors → (m, 3, 3) (Rodrigues, vectorized)."""
    theta = np.linalg.norm(rotvecs, axis=1)
    safe = np.where(theta > 0.0, theta, 1.0)
    k = rotvecs / safe[:, None]
    kx = np.zeros((rotvecs.shape[0], 3, 3))
    kx[:, 0, 1], kx[:, 0, 2], kx[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    kx -= kx.transpose(0, 2, 1)
    s, c = np.sin(theta)[:, None, None], (1.0 - np.cos(theta))[:, None, None]
    return np.eye(3) + s * kx + c * (kx @ kx)


def _sp_valid(cfg: AssemblerConfig, rotations: np.ndarray, translations: np.ndarray) -> np.ndarray:
    """Whether each relative pose (top plate in the bottom plate's frame) is a valid pose of
    every platform of the stack: lengths in stroke, deflections within the limit at both
    ends, top joints above bottom joints.

    Args:
        rotations: (m, 3, 3); translations: (m, 3) [m].

    Returns:
        (m,) booleans.
    """
    geo = _geometry(cfg)
    leg = cfg.leg
    bottom = geo.bottom_in_plate  # (n, 6, 3)
    top = geo.top_in_plate
    home = geo.home_direction
    # top joints in the bottom frame: (m, n, 6, 3)
    top_b = np.einsum("mab,nib->mnia", rotations, top) + translations[:, None, None, :]
    vec = top_b - bottom[None]
    lengths = np.linalg.norm(vec, axis=-1)
    u = vec / lengths[..., None]
    u_top = np.einsum("mnia,mab->mnib", u, rotations)  # direction in the top plate's frame
    cos_b = np.einsum("mnia,nia->mni", u, home)
    cos_t = np.einsum("mnia,nia->mni", u_top, home)
    cos_max = math.cos(leg.max_deflection)
    ok = (
        (lengths >= leg.min_length)
        & (lengths <= leg.max_length)
        & (cos_b >= cos_max)
        & (cos_t >= cos_max)
        & (vec[..., 2] > 0.0)
    )
    return ok.reshape(ok.shape[0], -1).all(axis=1)


def _about_mid_height(rotations: np.ndarray, d: float) -> tuple[np.ndarray, np.ndarray]:
    """Relative poses ``T(d/2)·R·T(d/2)`` of an SP tilted about its mid-height point."""
    half = np.array([0.0, 0.0, 0.5 * d])
    return rotations, half + rotations @ half


def _bisect_angles(cfg: AssemblerConfig, axes: np.ndarray, d: float, upper: float = 0.5 * math.pi) -> np.ndarray:
    """Largest angle θ in [0, upper] along each unit axis (m, 3) such that the SP rotated by
    ``exp3(θ·axis)`` about its mid-height point at height d stays valid (bisection, all axes
    at once). Returns 0 where the level SP itself is invalid."""
    m = axes.shape[0]
    lo = np.zeros(m)
    hi = np.full(m, upper)

    def valid(angles: np.ndarray) -> np.ndarray:
        rots = _rotations(angles[:, None] * axes)
        return _sp_valid(cfg, *_about_mid_height(rots, d))

    if not valid(lo).all():
        return np.zeros(m)
    top_ok = valid(hi)
    while (hi - lo).max() > _BISECTION_TOL:
        mid = 0.5 * (lo + hi)
        ok = valid(mid)
        lo = np.where(ok, mid, lo)
        hi = np.where(ok, hi, mid)
    return np.where(top_ok, upper, lo)


@functools.lru_cache(maxsize=256)
def cluster_limits(cfg: AssemblerConfig, link_length: float) -> tuple[float, float]:
    """Joint limits of one helper-arm cluster at link length ``d`` [rad].

    Derived numerically from the leg stroke and deflection limit: the tilt limit is the
    smallest, over 24 horizontal axes (every 15°), of the largest tilt of an SP about its
    mid-height point (relative pose ``T(d/2)·exp3(θ·a)·T(d/2)``) that keeps every leg of
    every platform within ``[min_length, max_length]``, both deflections within
    ``max_deflection`` and the top joints above the bottom ones (bisection to 1e-10 rad).
    The twist limit is the same for a rotation about z, smallest of both signs.

    Returns:
        (tilt limit for the x and y joints, twist limit for the z joint) [rad]; the joint
        ranges are ``[-limit, +limit]``. Both are 0 when a level SP cannot have height d.
    """
    phi = np.deg2rad(np.arange(_AXIS_COUNT) * (360.0 / _AXIS_COUNT))
    tilt_axes = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
    twist_axes = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    tilt = float(_bisect_angles(cfg, tilt_axes, link_length).min())
    twist = float(_bisect_angles(cfg, twist_axes, link_length).min())
    return tilt, twist


@functools.lru_cache(maxsize=32)
def height_range(cfg: AssemblerConfig) -> tuple[float, float]:
    """Heights ``[d_min, d_max]`` a level SP (plates parallel, no twist) can have [m].

    Found by bisection on each side of the home height with the same validity test as
    :func:`cluster_limits`; the helper arm's link length is kept within this range.
    """
    d0 = cfg.home_height

    def valid(d: float) -> bool:
        return bool(_sp_valid(cfg, np.eye(3)[None], np.array([[0.0, 0.0, d]]))[0])

    def edge(inside: float, outside: float) -> float:
        while abs(outside - inside) > _BISECTION_TOL:
            mid = 0.5 * (inside + outside)
            inside, outside = (mid, outside) if valid(mid) else (inside, mid)
        return inside

    return edge(d0, 0.0), edge(d0, 2.0 * cfg.leg.max_length)


# ---------------------------------------------------------------------- URDF
def _fmt(x: float) -> str:
    x = float(x)
    return "0" if x == 0.0 else repr(round(x, 15))


def helper_arm_urdf(cfg: AssemblerConfig, link_length: float | None = None) -> str:
    """URDF text of the helper arm of a configuration (see the module docstring).

    Links ``plate_0`` (root, the base plate's frame) … ``plate_n`` (tip = end effector);
    joints ``sp{j}_rx``, ``sp{j}_ry``, ``sp{j}_rz`` (revolute about x, y, z, co-located
    at the mid-height point of SP j), limits from :func:`cluster_limits`; the clusters'
    last link is ``sp{j}_cluster``. A kinematic model: links carry visual shapes (a
    cylinder along each link, a sphere at each cluster) but no inertia.

    Args:
        link_length: distance d between clusters [m]; default the home SP height.
    """
    d = cfg.home_height if link_length is None else float(link_length)
    if not (math.isfinite(d) and d > 0.0):
        raise ValueError(f"helper arm link length must be a positive number of metres, got {link_length!r}")
    tilt, twist = cluster_limits(cfg, d)
    n = cfg.platforms
    robot = ET.Element("robot", name="helper_arm")
    robot.append(
        ET.Comment(
            f" Helper arm of a {n}-platform Assembler (paper III): 3 revolute joints (x, y, z) per "
            f"cluster, clusters {_fmt(d)} m apart; limits: tilt {_fmt(tilt)} rad, twist {_fmt(twist)} rad. "
        )
    )
    ET.SubElement(ET.SubElement(robot, "material", name="helper_grey"), "color", rgba="0.6 0.6 0.6 1")
    ET.SubElement(ET.SubElement(robot, "material", name="helper_blue"), "color", rgba="0.2 0.3 0.9 1")

    def link(name: str, half_link_below: bool, half_link_above: bool, sphere: bool = False) -> None:
        el = ET.SubElement(robot, "link", name=name)
        for below, present in ((True, half_link_below), (False, half_link_above)):
            if not present:
                continue
            vis = ET.SubElement(el, "visual")
            ET.SubElement(vis, "origin", xyz=f"0 0 {_fmt(-d / 4 if below else d / 4)}", rpy="0 0 0")
            ET.SubElement(ET.SubElement(vis, "geometry"), "cylinder", radius="0.01", length=_fmt(d / 2))
            ET.SubElement(vis, "material", name="helper_grey")
        if sphere:
            vis = ET.SubElement(el, "visual")
            ET.SubElement(vis, "origin", xyz="0 0 0", rpy="0 0 0")
            ET.SubElement(ET.SubElement(vis, "geometry"), "sphere", radius="0.02")
            ET.SubElement(vis, "material", name="helper_blue")

    def joint(name: str, kind: str, parent: str, child: str, z: float, axis: str | None, limit: float) -> None:
        el = ET.SubElement(robot, "joint", name=name, type=kind)
        ET.SubElement(el, "parent", link=parent)
        ET.SubElement(el, "child", link=child)
        ET.SubElement(el, "origin", xyz=f"0 0 {_fmt(z)}", rpy="0 0 0")
        if axis is not None:
            ET.SubElement(el, "axis", xyz=axis)
            ET.SubElement(el, "limit", lower=_fmt(-limit), upper=_fmt(limit), effort="0", velocity="0")

    link("plate_0", False, True)
    for j in range(n):
        parent = f"plate_{j}"
        for axis_name, axis, lim in (("x", "1 0 0", tilt), ("y", "0 1 0", tilt), ("z", "0 0 1", twist)):
            child = f"sp{j}_cluster" if axis_name == "z" else f"sp{j}_r{axis_name}_link"
            if axis_name == "z":
                link(child, True, True, sphere=True)
            else:
                link(child, False, False)
            joint(f"sp{j}_r{axis_name}", "revolute", parent, child, d / 2 if axis_name == "x" else 0.0, axis, lim)
            parent = child
        link(f"plate_{j + 1}", True, j + 1 < n)
        joint(f"plate_{j + 1}_mount", "fixed", parent, f"plate_{j + 1}", d / 2, None, 0.0)
    ET.indent(robot, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"


# ---------------------------------------------------------------------- arm IK
@dataclass
class ArmIKResult:
    """Result of the helper arm's IK.

    Attributes:
        success: the tip reached the goal within the tolerance.
        q: (3n,) joint angles [rad] (the best found, also on failure).
        position_error: |tip - goal| [m]; rotation_error: angle of tip vs goal [rad].
        evaluations: residual evaluations spent; restarts: starts tried.
        message: "reached" or why not.
    """

    success: bool
    q: np.ndarray
    position_error: float
    rotation_error: float
    evaluations: int
    restarts: int
    message: str


class HelperArm:
    """The helper arm for one configuration and link length d, with its Pinocchio model.

    Attributes:
        config: the stack configuration; link_length: d [m].
        urdf_text: the URDF it was built from (:func:`helper_arm_urdf`).
        model, data: Pinocchio model (3n revolute joints) and its data.
        tilt_limit, twist_limit: joint limits [rad] (:func:`cluster_limits`).
        lower, upper: (3n,) joint limits as read back from the model [rad].
        plate_frames: frame ids of ``plate_0`` … ``plate_n``.
        cluster_joints: joint ids of the x joint of each cluster (its origin is the cluster).
    """

    def __init__(self, config: AssemblerConfig, link_length: float | None = None) -> None:
        self.config = config
        self.link_length = config.home_height if link_length is None else float(link_length)
        self.urdf_text = helper_arm_urdf(config, self.link_length)
        self.tilt_limit, self.twist_limit = cluster_limits(config, self.link_length)
        self.model = pin.buildModelFromXML(self.urdf_text)
        self.data = self.model.createData()
        self.lower = self.model.lowerPositionLimit.copy()
        self.upper = self.model.upperPositionLimit.copy()
        n = config.platforms
        self.plate_frames = [self.model.getFrameId(f"plate_{k}") for k in range(n + 1)]
        self.tip_frame = self.plate_frames[-1]
        self.cluster_joints = [self.model.getJointId(f"sp{j}_rx") for j in range(n)]
        self._geometry = _geometry(config)

    @property
    def nq(self) -> int:
        return self.model.nq

    def forward(self, q: npt.ArrayLike, base: pin.SE3 | None = None) -> tuple[list[pin.SE3], np.ndarray]:
        """Plate frames and arm points for joint angles q (Pinocchio FK).

        Args:
            q: (3n,) joint angles [rad].
            base: world pose of plate 0 (default identity).

        Returns:
            (world poses of plates 0..n, (n+2, 3) world points: base, clusters, tip).
        """
        base = pin.SE3.Identity() if base is None else base
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        plates = [base * self.data.oMf[f] for f in self.plate_frames]
        points = [plates[0].translation]
        points += [base.act(self.data.oMi[j].translation) for j in self.cluster_joints]
        points.append(plates[-1].translation)
        return plates, np.array(points)

    def _error(self, q: np.ndarray, goal_inv: pin.SE3) -> tuple[np.ndarray, pin.SE3]:
        pin.framesForwardKinematics(self.model, self.data, q)
        m = goal_inv * self.data.oMf[self.tip_frame]
        return pin.log6(m).vector, m

    def stack_violation(self, q: npt.ArrayLike, margin: float = 0.0) -> np.ndarray:
        """How far each leg of the stack would be past its limits with the plates on the arm.

        SP j's relative pose is ``T(d/2)·Rx(q[3j])·Ry(q[3j+1])·Rz(q[3j+2])·T(d/2)`` (computed
        here in numpy, vectorized over the platforms). For every leg: the amounts below
        ``min_length``, above ``max_length`` [m], past ``max_deflection`` at the bottom and
        top joint (as ``cos(max_deflection) - cos(θ)``, smooth where θ = 0 [1]), and the
        top joint's drop below the bottom joint [m], each bound tightened by ``margin``
        ([m], or [rad] for the deflection) so that a zero result keeps that far inside.

        Returns:
            (5, n, 6) non-negative amounts, zero where the constraint holds.
        """
        q = np.asarray(q, dtype=float).reshape(-1, 3)
        rot = _xyz_rotations(q)
        half = np.array([0.0, 0.0, 0.5 * self.link_length])
        trans = half + rot @ half
        geo = self._geometry
        leg = self.config.leg
        top_b = np.einsum("nab,nib->nia", rot, geo.top_in_plate) + trans[:, None, :]
        vec = top_b - geo.bottom_in_plate
        lengths = np.linalg.norm(vec, axis=-1)
        u = vec / lengths[..., None]
        u_top = np.einsum("nia,nab->nib", u, rot)
        cos_limit = math.cos(leg.max_deflection - margin)
        cos_b = (u * geo.home_direction).sum(axis=-1)
        cos_t = (u_top * geo.home_direction).sum(axis=-1)
        out = np.stack(
            [
                leg.min_length + margin - lengths,
                lengths - leg.max_length + margin,
                cos_limit - cos_b,
                cos_limit - cos_t,
                margin - vec[..., 2],
            ]
        )
        return np.maximum(out, 0.0)

    def _penalty_jacobian(self, q: np.ndarray, base_value: np.ndarray, margin: float, step: float = 1e-7) -> np.ndarray:
        """Forward-difference Jacobian of :meth:`stack_violation` (flattened) w.r.t. q.

        SP j depends only on cluster j, so the three columns of all clusters are perturbed at
        once (3 evaluations)."""
        n = self.config.platforms
        flat = base_value.reshape(5, n, 6)
        jac = np.zeros((5, n, 6, n, 3))
        for k in range(3):
            dq = q.copy()
            dq[k::3] += step
            diff = (self.stack_violation(dq, margin) - flat) / step  # (5, n, 6)
            jac[:, np.arange(n), :, np.arange(n), k] = diff.transpose(1, 0, 2)
        return jac.reshape(30 * n, 3 * n)

    def ik(
        self,
        goal: pin.SE3,
        base: pin.SE3 | None = None,
        q0: npt.ArrayLike | None = None,
        regularization: float = 0.05,
        constraint_weight: float = 10.0,
        margin: float = 1e-5,
        tolerance: float = 1e-10,
        restarts: int = 2,
        seed: int = 0,
    ) -> ArmIKResult:
        """Joint angles that put the tip at ``goal``, within the joint limits and, as far as
        possible, with the plates a valid pose of the stack.

        Bounded least squares (``trf``, bounds = joint limits) on the residual
        ``[log6(goal⁻¹·tip(q)), c·v(q), w·q]`` with the analytic Jacobian
        ``Jlog6·J_tip`` (Pinocchio, LOCAL frame) for the goal error. ``v(q)`` is
        :meth:`stack_violation` (the stack's leg constraints as a penalty, so the solve is
        constrained by them as well as by the joint limits; forward differences), and the
        pull ``w·q`` spreads the bending evenly over the clusters. A second solve without
        the pull then reaches the goal exactly. Starts at ``q0`` (default 0), then at up to
        ``restarts`` deterministic random points within half the limits.

        Args:
            goal: world pose of the tip (the EE) [m, rad].
            base: world pose of plate 0 (default identity).
            regularization: w [m/rad]; constraint_weight: c [1].
            margin: distance kept from the stack's bounds [m or rad].
            tolerance: largest |log6| error (translation [m] and rotation [rad] parts) to
                count as reached.
            seed: seed of the restart points.

        Returns:
            An :class:`ArmIKResult`; ``success`` needs the goal reached *and* the stack's
            leg constraints met (:meth:`stack_violation` zero).
        """
        base = pin.SE3.Identity() if base is None else base
        goal_inv = (base.actInv(goal)).inverse()
        n_q = self.nq
        lo, hi = self.lower, self.upper
        w_eye = np.eye(n_q)
        evaluations = 0

        def solve(start: np.ndarray, w: float, loose: bool) -> np.ndarray:
            def fun(q: np.ndarray) -> np.ndarray:
                nonlocal evaluations
                evaluations += 1
                err, _ = self._error(q, goal_inv)
                parts = [err, constraint_weight * self.stack_violation(q, margin).ravel()]
                if w > 0:
                    parts.append(w * q)
                return np.concatenate(parts)

            def jac(q: np.ndarray) -> np.ndarray:
                _, m = self._error(q, goal_inv)
                pin.computeJointJacobians(self.model, self.data, q)
                j_tip = pin.getFrameJacobian(self.model, self.data, self.tip_frame, pin.LOCAL)
                value = self.stack_violation(q, margin)
                parts = [pin.Jlog6(m) @ j_tip, constraint_weight * self._penalty_jacobian(q, value, margin)]
                if w > 0:
                    parts.append(w * w_eye)
                return np.vstack(parts)

            # the pulled solve only has to land near the spread-out solution; the exact one polishes
            tol = 1e-6 if loose else 1e-15
            res = least_squares(
                fun, np.clip(start, lo, hi), jac=jac, bounds=(lo, hi), method="trf",
                ftol=tol, xtol=tol, gtol=tol, max_nfev=60 if loose else 30,
            )  # fmt: skip
            return res.x

        rng = np.random.default_rng(seed)
        starts = [np.zeros(n_q) if q0 is None else np.asarray(q0, dtype=float)]
        starts += [rng.uniform(0.5 * lo, 0.5 * hi) for _ in range(restarts)]
        best: tuple[float, np.ndarray, float, float, float] | None = None
        for k, start in enumerate(starts):
            q = solve(start, regularization, True) if regularization > 0 else start
            q = solve(q, 0.0, False)
            err, _ = self._error(q, goal_inv)
            pos, rot = float(np.linalg.norm(err[:3])), float(np.linalg.norm(err[3:]))
            viol = float(self.stack_violation(q).max())
            score = pos + rot + viol
            if best is None or score < best[0]:
                best = (score, q, pos, rot, viol)
            if pos <= tolerance and rot <= tolerance and viol == 0.0:
                return ArmIKResult(True, q, pos, rot, evaluations, k + 1, "reached")
        assert best is not None
        _, q, pos, rot, viol = best
        if pos <= tolerance and rot <= tolerance:
            why = f"reaches the goal only with plates past the stack's limits (by up to {viol:.3g})"
        else:
            why = f"cannot reach the goal within its joint limits: closest {pos:.3g} m, {rot:.3g} rad away"
        return ArmIKResult(
            False, q, pos, rot, evaluations, len(starts), f"the helper arm (d = {self.link_length:.4f} m) {why}"
        )


def _xyz_rotations(q: np.ndarray) -> np.ndarray:
    """Rx(a)·Ry(b)·Rz(c) for each row (a, b, c) of q (m, 3) → (m, 3, 3)."""
    ca, sa = np.cos(q[:, 0]), np.sin(q[:, 0])
    cb, sb = np.cos(q[:, 1]), np.sin(q[:, 1])
    cc, sc = np.cos(q[:, 2]), np.sin(q[:, 2])
    rot = np.empty((q.shape[0], 3, 3))
    rot[:, 0, 0] = cb * cc
    rot[:, 0, 1] = -cb * sc
    rot[:, 0, 2] = sb
    rot[:, 1, 0] = ca * sc + sa * sb * cc
    rot[:, 1, 1] = ca * cc - sa * sb * sc
    rot[:, 1, 2] = -sa * cb
    rot[:, 2, 0] = sa * sc - ca * sb * cc
    rot[:, 2, 1] = sa * cc + ca * sb * sc
    rot[:, 2, 2] = ca * cb
    return rot


@functools.lru_cache(maxsize=64)
def _cached_arm(cfg: AssemblerConfig, link_length: float) -> HelperArm:
    return HelperArm(cfg, link_length)


# ---------------------------------------------------------------------- initial condition
@dataclass
class HelperArmOptions:
    """Options of :func:`initial_condition`.

    Attributes:
        d_step: step s of the link-length scan d0, d0+s, d0-s, d0+2s, … [m].
        max_attempts: recursion limit: the most arm solves (values of d) tried.
        tolerance: EE goal tolerance of the returned state [m, rad].
        regularization: weight w of the pull of the joints toward 0 [m/rad].
        constraint_weight: weight of the stack's leg constraints in the arm IK
            (:meth:`HelperArm.ik`).
        arm_tolerance: the arm counts as reaching the goal within this error [m, rad].
        restarts: extra deterministic starts of the arm IK per d.
    """

    d_step: float = 0.01
    max_attempts: int = 15
    tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(1e-9, 1e-9))
    regularization: float = 0.05
    constraint_weight: float = 10.0
    arm_tolerance: float = 1e-10
    restarts: int = 0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.d_step) and self.d_step > 0.0):
            raise ValueError(f"d_step must be a positive number of metres, got {self.d_step!r}")
        if int(self.max_attempts) < 1:
            raise ValueError(f"max_attempts must be >= 1, got {self.max_attempts!r}")


@dataclass
class InitialConditionResult:
    """The initial pose of the stack for a goal, from the helper arm.

    Attributes:
        success: True only when the state satisfies every kinematic constraint
            (:data:`KINEMATIC_VIOLATIONS`: leg limits, joint deflection, continuous
            translation, EE at the goal, no singular platform). Force limits are *not*
            required: they are reported in ``state`` (``state.feasible`` requires them too).
        message: what happened; the reason on failure.
        goal: the EE goal (world pose).
        state: the valid state, or the home state (checked against the goal) on failure.
        leg_lengths: (n, 6) leg lengths of ``state`` [m].
        arm_q: (3n,) helper-arm joint angles used [rad] (on failure: of the last arm
            solution tried, if any).
        link_length: the d that worked [m] (None on failure).
        attempts: arm solves (values of d) tried.
        time_s: wall time [s].
        arm_points: (n+2, 3) world points of the arm used: base, the n clusters, tip.
    """

    success: bool
    message: str
    goal: pin.SE3
    state: StackState
    leg_lengths: np.ndarray
    arm_q: np.ndarray | None
    link_length: float | None
    attempts: int
    time_s: float
    arm_points: np.ndarray | None = None


def _d_sequence(d0: float, step: float, d_range: tuple[float, float]):
    """d0, d0+s, d0-s, d0+2s, … within ``d_range``, stopping when both sides are out."""
    lo, hi = d_range
    if lo <= d0 <= hi:
        yield d0
    k = 1
    while True:
        up, down = d0 + k * step, d0 - k * step
        if up > hi and down < lo:
            return
        if up <= hi:
            yield up
        if down >= lo:
            yield down
        k += 1


def initial_condition(
    am: AssemblerModel,
    goal: pin.SE3 | npt.ArrayLike,
    options: HelperArmOptions | None = None,
) -> InitialConditionResult:
    """A valid initial pose of the whole stack for an EE goal, by the helper arm (paper §III).

    See the module docstring for the algorithm. Plate 0 stays at ``am.home[0]``; plate n is
    put exactly at ``goal``; plates 1..n-1 at the arm's link midpoints.

    Args:
        am: the stack model.
        goal: world pose of the EE (``pin.SE3`` or 4×4).
        options: scan step, recursion limit, tolerances.

    Returns:
        An :class:`InitialConditionResult` (``success`` False with the reason when no valid
        pose was found: the state is then the home pose).

    Raises:
        PoseError: the goal is not a finite SE(3) pose.
    """
    t0 = time.perf_counter()
    goal_se3 = to_se3(goal, "goal")
    opts = options or HelperArmOptions()
    cfg = am.config
    base = am.home[0]
    n = am.n
    d0 = cfg.home_height
    attempts = 0
    broken: list[str] = []  # attempts where the arm reached the goal but the plates were invalid
    closest, closest_error = "", math.inf
    last_q: np.ndarray | None = None
    last_points: np.ndarray | None = None
    for d in _d_sequence(d0, opts.d_step, height_range(cfg)):
        if attempts >= opts.max_attempts:
            break
        tilt, twist = cluster_limits(cfg, d)
        if tilt <= 0.0 and twist <= 0.0:
            continue
        attempts += 1
        arm = _cached_arm(cfg, round(d, 12))
        ik = arm.ik(
            goal_se3, base, regularization=opts.regularization, constraint_weight=opts.constraint_weight,
            tolerance=opts.arm_tolerance, restarts=opts.restarts,
        )  # fmt: skip
        last_q = ik.q
        if not ik.success:
            if ik.position_error <= opts.arm_tolerance and ik.rotation_error <= opts.arm_tolerance:
                broken.append(f"d={d:.4f}: stack limits")
            elif ik.position_error + ik.rotation_error < closest_error:
                closest_error = ik.position_error + ik.rotation_error
                closest = f"closest: {ik.position_error:.3g} m, {ik.rotation_error:.3g} rad away at d = {d:.4f} m"
            logger.debug("initial condition: %s", ik.message)
            continue
        plates, points = arm.forward(ik.q, base)
        last_points = points
        plates[n] = goal_se3.copy()
        pa = PlateArrays(np.array([m.rotation for m in plates]), np.array([m.translation for m in plates]))
        legs = leg_state(am, pa)
        kin = evaluate_constraints(cfg, legs, None, pa, goal_se3, opts.tolerance)
        if kin:
            kinds = sorted({v.kind for v in kin})
            broken.append(f"d={d:.4f}: {', '.join(kinds)}")
            logger.debug("initial condition at d=%.4f: %d kinematic violation(s) %s", d, len(kin), kinds)
            continue
        state = evaluate_state(am, pa, goal=goal_se3, tolerance=opts.tolerance)
        bad = [v for v in state.violations if v.kind in KINEMATIC_VIOLATIONS]
        if bad:
            broken.append(f"d={d:.4f}: {bad[0]}")
            continue
        dt = time.perf_counter() - t0
        logger.info("initial condition found at d=%.4f m after %d attempt(s) in %.1f ms", d, attempts, 1e3 * dt)
        return InitialConditionResult(
            True,
            f"valid initial condition with link length d = {d:.4f} m after {attempts} attempt(s)"
            + ("" if state.feasible else f" (force limits exceeded: {len(state.violations)} violation(s))"),
            goal_se3,
            state,
            state.leg_lengths.copy(),
            ik.q.copy(),
            float(d),
            attempts,
            dt,
            points,
        )
    state = evaluate_state(am, am.home, goal=goal_se3, tolerance=opts.tolerance)
    if attempts == 0:
        why = "no link length within the heights an SP can have was tried"
    elif broken:
        why = (
            "the helper arm reached the goal only with plates that break a kinematic constraint ("
            + "; ".join(broken[:3])
            + ("; …" if len(broken) > 3 else "")
            + ")"
        )
    else:
        why = f"the goal is out of the helper arm's reach within its joint limits ({closest})"
    message = f"no valid initial condition after {attempts} attempt(s) (d from {d0:.4f} m, step {opts.d_step} m): {why}"
    logger.info("initial condition failed: %s", message)
    return InitialConditionResult(
        False,
        message,
        goal_se3,
        state,
        state.leg_lengths.copy(),
        last_q,
        None,
        attempts,
        time.perf_counter() - t0,
        last_points,
    )
