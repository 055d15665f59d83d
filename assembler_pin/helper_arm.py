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
  (up to 100 evaluations) then drives the goal error to machine precision.
  **The link length d is a variable of the same solve** (``link_range``, bounded to
  :func:`height_range`; not pulled): every translation of the arm is ``d`` times one of
  the unit arm, so the tip moves by ``R_tipᵀ·p_tip/d`` (LOCAL) per unit of d and the
  model built for one d serves all. This removes the singularity of a straight arm,
  which cannot change its length by bending, and the need for the scan to hit the right
  d exactly (a straight-up goal at z is solved with d = z/n, q = 0). Optional
  deterministic restarts (``HelperArmOptions.restarts``, default none: they did not
  raise the success rate, nor did a start bent toward the goal).

* **Initial condition** (:func:`initial_condition`): the paper's recursive scan over d,
  each scan value being the *start* of d in the IK above: first ``d0`` (the paper's
  start), then ``d* = |p_goal - p_base| / n`` (the straight arm's length to the goal,
  clipped half a step inside :func:`height_range`) and ``d* + s, d* - s, d* + 2s, …``
  (``s`` the user step; values within s/2 of d0 are left out), until ``max_attempts``
  arm solves (the paper's recursion limit), skipping heights where a level SP cannot
  tilt or twist. When the arm reaches the goal with valid plates, plate n is put exactly
  at the goal and the leg lengths follow from the SP IK
  (:func:`~assembler_pin.kinematics.leg_state`), and every kinematic constraint of the
  stack is checked. When no scan value works (the arm model only tilts each SP about its
  mid-height point at one common height; it cannot shear an SP sideways, which low goals
  need), a **repair** on the stack itself follows: from the ``repair_starts`` (default 2)
  arm poses closest to valid (goal error + leg violation), then from the "even screw"
  pose (plate k at ``base·exp6(k/n · log6(base⁻¹·goal))``), plates 1..n-1 are moved
  (``least_squares`` on the legs' constraint violations, 1e-6 inside every bound, plates
  0 and n fixed) until every leg is valid, and the result is checked as above
  (``InitialConditionResult.repaired``). On failure the home pose is returned with
  ``success=False`` and the reason. Unreachable goals are answers, never exceptions;
  malformed goals raise :class:`~assembler_pin.exceptions.PoseError`.

  Measured on this machine (default options): straight-up goals z = 0.62..1.2 m all
  solved (z = 1.3 m is beyond the stack); level-EE goals x = -0.4..0.5, y = 0, 0.2,
  z = 0.5..1.0 m: 105/120 (the fixed-d scan: 39/120), the 15 failures all at
  z <= 0.6 m, 9 of them with no valid stack pose found by a 60-start search on the
  plates; stack FK goals of random leg lengths: 200/200 (full stroke and middle 80 %);
  median ≈ 10 ms per solved goal (repaired ones ≈ 0.5 s), failures < 1 s.

Frames: the arm's base is plate 0's world pose (``am.home[0]``, identity by default);
all poses returned are world poses. Units: metres and radians.
"""

from __future__ import annotations

import functools
import logging
import math
import numbers
import time
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from .config import AssemblerConfig
from .constraints import GoalTolerance, evaluate_constraints
from .exceptions import OptionsError
from .geometry import LegGeometry, leg_geometry, reach_bound
from .kinematics import PlateArrays, leg_state, to_se3
from .model import AssemblerModel
from .state import StackState, evaluate_state
from .validation import is_number

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
    "perturbed_plates",
    "repair_stack",
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
        raise OptionsError(f"helper arm link length must be a positive number of metres, got {link_length!r}")
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
        success: the tip reached the goal within the tolerance with the stack's leg
            constraints met.
        q: (3n,) joint angles [rad] (the best found, also on failure).
        position_error: |tip - goal| [m]; rotation_error: angle of tip vs goal [rad].
        evaluations: residual evaluations spent; restarts: starts tried.
        message: "reached" or why not.
        link_length: the link length d of ``q`` [m]: the arm's own d, or the one the solve
            chose when d was a variable (``link_range``). None only for results built by hand.
    """

    success: bool
    q: np.ndarray
    position_error: float
    rotation_error: float
    evaluations: int
    restarts: int
    message: str
    link_length: float | None = None


class HelperArm:
    """The helper arm for one configuration and link length d, with its Pinocchio model.

    Every translation of the arm is a multiple of d and its rotations do not depend on d,
    so the same model also gives the arm of any other link length d' by scaling every
    position by d'/d (used when d is a variable of :meth:`ik`).

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

    def forward(
        self, q: npt.ArrayLike, base: pin.SE3 | None = None, link_length: float | None = None
    ) -> tuple[list[pin.SE3], np.ndarray]:
        """Plate frames and arm points for joint angles q (Pinocchio FK).

        Args:
            q: (3n,) joint angles [rad].
            base: world pose of plate 0 (default identity).
            link_length: d [m] if not the arm's own (positions scale with d).

        Returns:
            (world poses of plates 0..n, (n+2, 3) world points: base, clusters, tip).
        """
        base = pin.SE3.Identity() if base is None else base
        scale = 1.0 if link_length is None else float(link_length) / self.link_length
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))

        def scaled(m: pin.SE3) -> pin.SE3:
            return pin.SE3(m.rotation, scale * m.translation)

        plates = [base * scaled(self.data.oMf[f]) for f in self.plate_frames]
        points = [plates[0].translation]
        points += [base.act(scale * self.data.oMi[j].translation) for j in self.cluster_joints]
        points.append(plates[-1].translation)
        return plates, np.array(points)

    def _error(self, q: np.ndarray, goal_inv: pin.SE3, scale: float = 1.0) -> tuple[np.ndarray, pin.SE3]:
        """log6 goal error of the tip and ``goal⁻¹·tip`` for the arm scaled by ``scale``."""
        pin.framesForwardKinematics(self.model, self.data, q)
        tip = self.data.oMf[self.tip_frame]
        m = goal_inv * (tip if scale == 1.0 else pin.SE3(tip.rotation, scale * tip.translation))
        return pin.log6(m).vector, m

    def stack_violation(self, q: npt.ArrayLike, margin: float = 0.0, link_length: float | None = None) -> np.ndarray:
        """How far each leg of the stack would be past its limits with the plates on the arm.

        SP j's relative pose is ``T(d/2)·Rx(q[3j])·Ry(q[3j+1])·Rz(q[3j+2])·T(d/2)`` (computed
        here in numpy, vectorized over the platforms). For every leg: the amounts below
        ``min_length``, above ``max_length`` [m], past ``max_deflection`` at the bottom and
        top joint (as ``cos(max_deflection) - cos(θ)``, smooth where θ = 0 [1]), and the
        top joint's drop below the bottom joint [m], each bound tightened by ``margin``
        ([m], or [rad] for the deflection) so that a zero result keeps that far inside.

        Args:
            link_length: d [m] if not the arm's own.

        Returns:
            (5, n, 6) non-negative amounts, zero where the constraint holds.
        """
        q = np.asarray(q, dtype=float).reshape(-1, 3)
        rot = _xyz_rotations(q)
        d = self.link_length if link_length is None else float(link_length)
        half = np.array([0.0, 0.0, 0.5 * d])
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

    def _penalty_jacobian(
        self,
        q: np.ndarray,
        base_value: np.ndarray,
        margin: float,
        step: float = 1e-7,
        link_length: float | None = None,
        with_d: bool = False,
    ) -> np.ndarray:
        """Forward-difference Jacobian of :meth:`stack_violation` (flattened) w.r.t. q (and d
        as a last column when ``with_d``).

        SP j depends only on cluster j, so the three columns of all clusters are perturbed at
        once (3 evaluations, one more for d)."""
        n = self.config.platforms
        flat = base_value.reshape(5, n, 6)
        jac = np.zeros((5, n, 6, n, 3))
        for k in range(3):
            dq = q.copy()
            dq[k::3] += step
            diff = (self.stack_violation(dq, margin, link_length) - flat) / step  # (5, n, 6)
            jac[:, np.arange(n), :, np.arange(n), k] = diff.transpose(1, 0, 2)
        jac = jac.reshape(30 * n, 3 * n)
        if not with_d:
            return jac
        d = self.link_length if link_length is None else float(link_length)
        col = (self.stack_violation(q, margin, d + step) - flat).reshape(-1, 1) / step
        return np.hstack([jac, col])

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
        link_range: tuple[float, float] | None = None,
    ) -> ArmIKResult:
        """Joint angles (and, optionally, the link length) that put the tip at ``goal``,
        within the joint limits and, as far as possible, with the plates a valid pose of the
        stack.

        Bounded least squares (``trf``, bounds = joint limits) on the residual
        ``[log6(goal⁻¹·tip(q)), c·v(q), w·q]`` with the analytic Jacobian
        ``Jlog6·J_tip`` (Pinocchio, LOCAL frame) for the goal error. ``v(q)`` is
        :meth:`stack_violation` (the stack's leg constraints as a penalty, so the solve is
        constrained by them as well as by the joint limits; forward differences), and the
        pull ``w·q`` spreads the bending evenly over the clusters. A second solve without
        the pull then reaches the goal exactly.

        With ``link_range`` the link length d is a variable too, bounded to that range and
        started at the arm's own d: the tip's translation is ``(d/d_arm)·p_tip(q)`` and its
        rotation does not depend on d, so the tip twist per unit d is
        ``[R_tipᵀ·p_tip/d_arm, 0]`` (LOCAL frame) and the LOCAL Jacobian's linear rows scale
        by ``d/d_arm``. This removes the singularity of changing a straight arm's length.

        Starts: ``q0`` (default 0), then up to ``restarts`` deterministic random points
        within half the limits (with d at the arm's own). Stops at the first start that
        succeeds.

        Args:
            goal: world pose of the tip (the EE) [m, rad].
            base: world pose of plate 0 (default identity).
            regularization: w [m/rad]; constraint_weight: c [1].
            margin: distance kept from the stack's bounds [m or rad].
            tolerance: largest |log6| error (translation [m] and rotation [rad] parts) to
                count as reached.
            seed: seed of the restart points.
            link_range: (lowest, highest) link length d [m] when d is a variable.

        Returns:
            An :class:`ArmIKResult`; ``success`` needs the goal reached *and* the stack's
            leg constraints met (:meth:`stack_violation` zero); ``link_length`` is the d used.
        """
        base = pin.SE3.Identity() if base is None else base
        goal_inv = (base.actInv(goal)).inverse()
        n_q = self.nq
        d_arm = self.link_length
        free_d = link_range is not None
        lo, hi = self.lower, self.upper
        if free_d:
            d_lo, d_hi = float(min(link_range)), float(max(link_range))
            if not d_lo <= d_arm <= d_hi:
                raise OptionsError(f"link_range {link_range!r} must contain the arm's link length {d_arm}")
            lo, hi = np.append(lo, d_lo), np.append(hi, d_hi)
        evaluations = 0
        statuses: list[int] = []

        def split(x: np.ndarray) -> tuple[np.ndarray, float]:
            return (x[:n_q], float(x[n_q])) if free_d else (x, d_arm)

        def solve(start: np.ndarray, w: float, loose: bool) -> np.ndarray:
            w_diag = np.diag(np.append(np.full(n_q, w), 0.0) if free_d else np.full(n_q, w))

            def fun(x: np.ndarray) -> np.ndarray:
                nonlocal evaluations
                evaluations += 1
                q, d = split(x)
                err, _ = self._error(q, goal_inv, d / d_arm)
                parts = [err, constraint_weight * self.stack_violation(q, margin, d).ravel()]
                if w > 0:
                    parts.append(w_diag @ x)
                return np.concatenate(parts)

            def jac(x: np.ndarray) -> np.ndarray:
                q, d = split(x)
                scale = d / d_arm
                _, m = self._error(q, goal_inv, scale)
                pin.computeJointJacobians(self.model, self.data, q)
                j_tip = pin.getFrameJacobian(self.model, self.data, self.tip_frame, pin.LOCAL)
                if free_d:
                    tip = self.data.oMf[self.tip_frame]
                    j_tip = np.vstack([scale * j_tip[:3], j_tip[3:]])
                    j_d = np.concatenate([tip.rotation.T @ tip.translation / d_arm, np.zeros(3)])
                    j_tip = np.hstack([j_tip, j_d[:, None]])
                value = self.stack_violation(q, margin, d)
                j_pen = self._penalty_jacobian(q, value, margin, link_length=d, with_d=free_d)
                parts = [pin.Jlog6(m) @ j_tip, constraint_weight * j_pen]
                if w > 0:
                    parts.append(w_diag)
                return np.vstack(parts)

            # the pulled solve only has to land near the spread-out solution; the exact one polishes
            tol = 1e-6 if loose else 1e-15
            from scipy.optimize import least_squares  # on first use: fast start-up

            res = least_squares(
                fun, np.clip(start, lo, hi), jac=jac, bounds=(lo, hi), method="trf",
                ftol=tol, xtol=tol, gtol=tol, max_nfev=60 if loose else 100,
            )  # fmt: skip
            statuses.append(int(res.status))
            return res.x

        rng = np.random.default_rng(seed)
        starts = [np.zeros(n_q) if q0 is None else np.asarray(q0, dtype=float)]
        starts += [rng.uniform(0.5 * self.lower, 0.5 * self.upper) for _ in range(restarts)]
        best: tuple[float, np.ndarray, float, float, float, float] | None = None
        for k, start in enumerate(starts):
            x = np.append(start, d_arm) if free_d else start
            x = solve(x, regularization, True) if regularization > 0 else x
            x = solve(x, 0.0, False)
            q, d = split(x)
            err, _ = self._error(q, goal_inv, d / d_arm)
            pos, rot = float(np.linalg.norm(err[:3])), float(np.linalg.norm(err[3:]))
            viol = float(self.stack_violation(q, 0.0, d).max())
            score = pos + rot + viol
            if best is None or score < best[0]:
                best = (score, q, d, pos, rot, viol)
            if pos <= tolerance and rot <= tolerance and viol == 0.0:
                return ArmIKResult(True, q, pos, rot, evaluations, k + 1, "reached", d)
        assert best is not None
        _, q, d, pos, rot, viol = best
        logger.debug("arm IK failed; least_squares statuses %s", statuses)
        if pos <= tolerance and rot <= tolerance:
            why = f"reaches the goal only with plates past the stack's limits (by up to {viol:.3g})"
        else:
            why = f"cannot reach the goal within its joint limits: closest {pos:.3g} m, {rot:.3g} rad away"
        return ArmIKResult(False, q, pos, rot, evaluations, len(starts), f"the helper arm (d = {d:.4f} m) {why}", d)


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


# ---------------------------------------------------------------------- stack repair
def _leg_hinge(am: AssemblerModel, pa: PlateArrays, margin: float) -> np.ndarray:
    """Amounts by which every leg breaks a kinematic constraint, each bound tightened by
    ``margin``: below ``min_length``, above ``max_length`` [m], deflection past
    ``max_deflection`` at either end [rad], rise below zero [m]. Zero where valid."""
    legs = leg_state(am, pa)
    leg = am.config.leg
    return np.concatenate(
        [
            np.maximum(leg.min_length + margin - legs.lengths, 0.0).ravel(),
            np.maximum(legs.lengths - leg.max_length + margin, 0.0).ravel(),
            np.maximum(legs.deflection - leg.max_deflection + margin, 0.0).ravel(),
            np.maximum(margin - legs.rise, 0.0).ravel(),
        ]
    )


def repair_stack(
    am: AssemblerModel, start: list[pin.SE3], margin: float = 1e-6, max_nfev: int = 100
) -> tuple[PlateArrays, float]:
    """Move plates 1..n-1 from ``start`` until every leg of the stack is valid.

    Plates 0 and n stay where ``start`` has them (the base and the goal). Plate k becomes
    ``start_k·exp6(x_k)``; ``scipy.optimize.least_squares`` (``trf``, forward-difference
    Jacobian) drives the leg constraints' violation (:func:`_leg_hinge`, ``margin`` [m or
    rad] inside every bound) to zero from x = 0, so the plates move little.

    Returns:
        (the plates reached, the largest remaining violation [m or rad]; 0 means valid).
    """
    n = len(start) - 1
    rot0 = np.array([m.rotation for m in start])
    pos0 = np.array([m.translation for m in start])

    def plates(x: np.ndarray) -> PlateArrays:
        rot, pos = rot0.copy(), pos0.copy()
        for k in range(1, n):
            m = start[k] * pin.exp6(x[6 * (k - 1) : 6 * k])
            rot[k], pos[k] = m.rotation, m.translation
        return PlateArrays(rot, pos)

    from scipy.optimize import least_squares  # on first use: fast start-up

    res = least_squares(
        lambda x: _leg_hinge(am, plates(x), margin), np.zeros(6 * (n - 1)), method="trf",
        ftol=1e-15, xtol=1e-15, gtol=1e-15, max_nfev=max_nfev,
    )  # fmt: skip
    pa = plates(res.x)
    return pa, float(_leg_hinge(am, pa, 0.0).max())


# ---------------------------------------------------------------------- initial condition
@dataclass
class HelperArmOptions:
    """Options of :func:`initial_condition`.

    Attributes:
        d_step: step s of the link-length scan [m] (see :func:`initial_condition`).
        max_attempts: recursion limit: the most arm solves (scan values of d) tried.
        tolerance: EE goal tolerance of the returned state [m, rad].
        regularization: weight w of the pull of the joints toward 0 [m/rad].
        constraint_weight: weight of the stack's leg constraints in the arm IK
            (:meth:`HelperArm.ik`).
        arm_tolerance: the arm counts as reaching the goal within this error [m, rad].
        restarts: extra deterministic starts of the arm IK per d.
        free_link_length: let the arm IK move d continuously over the whole
            :func:`height_range`, starting at each scan value (False: d fixed at the scan
            values, the paper's scan exactly).
        repair_starts: after a scan without success, how many of the arm's closest poses
            (fewest goal error plus leg violation) are repaired on the stack itself
            (0: no repair).
        perturbed_starts: how many randomly perturbed copies of the even screw pose are
            repaired too, after the even pose itself (seeded).
    """

    d_step: float = 0.01
    max_attempts: int = 15
    tolerance: GoalTolerance = field(default_factory=lambda: GoalTolerance(1e-9, 1e-9))
    regularization: float = 0.05
    constraint_weight: float = 10.0
    arm_tolerance: float = 1e-10
    restarts: int = 0
    free_link_length: bool = True
    repair_starts: int = 2
    perturbed_starts: int = 8

    def __post_init__(self) -> None:
        for name in ("d_step", "regularization", "constraint_weight", "arm_tolerance"):
            value = getattr(self, name)
            if not (is_number(value) and math.isfinite(value) and value >= 0):
                raise OptionsError(f"{name} must be a finite number >= 0, got {value!r}")
        if not self.d_step > 0:
            raise OptionsError(f"d_step must be a positive number of metres, got {self.d_step!r}")
        for name, low in (("max_attempts", 1), ("restarts", 0), ("repair_starts", 0), ("perturbed_starts", 0)):
            value = getattr(self, name)
            if not (isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= low):
                raise OptionsError(f"{name} must be an integer >= {low}, got {value!r}")
        if not isinstance(self.tolerance, GoalTolerance):
            raise OptionsError(f"tolerance must be a GoalTolerance, got {self.tolerance!r}")


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
            solution tried, if any; None after a repair from the even screw pose).
        link_length: the d of the arm used [m] (None on failure, and after a repair from
            the even screw pose).
        attempts: arm solves (values of d) tried.
        time_s: wall time [s].
        arm_points: (n+2, 3) world points of the arm used: base, the n clusters, tip
            (None when no arm pose was used).
        repaired: the plates are the arm's closest pose moved onto a valid stack pose
            (then they are near, not exactly at, the arm's link midpoints).
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
    repaired: bool = False

    def plates_if_valid(self) -> PlateArrays | None:
        """The valid state's plate poses, None when no valid initial condition was found."""
        return self.state.plates if self.success else None


def perturbed_plates(plates: list[pin.SE3], count: int, seed: int = 0) -> list[list[pin.SE3]]:
    """``count`` copies of ``plates`` with plates 1..n-1 moved by random twists
    (±5 cm, ±0.3 rad per axis; seeded, so results are reproducible)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        moved = [m.copy() for m in plates]
        for k in range(1, len(plates) - 1):
            moved[k] = moved[k] * pin.exp6(np.concatenate([rng.uniform(-0.05, 0.05, 3), rng.uniform(-0.3, 0.3, 3)]))
        out.append(moved)
    return out


def _d_sequence(d0: float, step: float, d_range: tuple[float, float]) -> Iterator[float]:
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


def _d_scan(d0: float, distance: float, n: int, step: float, d_range: tuple[float, float]) -> Iterator[float]:
    """The link lengths tried [m]: the home height d0 first (the paper's start), then
    ``d* = distance/n`` (the straight arm's length to the goal point) clipped to half a step
    inside ``d_range``, then d*+s, d*-s, d*+2s, … within ``d_range``, leaving out the values
    within half a step of d0 (already tried)."""
    lo, hi = d_range
    if lo <= d0 <= hi:
        yield d0
    d_star = min(max(distance / n, lo + 0.5 * step), hi - 0.5 * step)
    for d in _d_sequence(d_star, step, d_range):
        if abs(d - d0) >= 0.5 * step:
            yield d


def _kinematic_problems(
    am: AssemblerModel, pa: PlateArrays, goal: pin.SE3, tolerance: GoalTolerance
) -> tuple[StackState | None, str]:
    """The state of plates ``pa`` if it meets every kinematic constraint, else (None, why)."""
    kin = evaluate_constraints(am.config, leg_state(am, pa), None, pa, goal, tolerance)
    if kin:
        return None, ", ".join(sorted({v.kind for v in kin}))
    state = evaluate_state(am, pa, goal=goal, tolerance=tolerance)
    bad = [v for v in state.violations if v.kind in KINEMATIC_VIOLATIONS]
    if bad:
        return None, str(bad[0])
    return state, ""


def initial_condition(
    am: AssemblerModel,
    goal: pin.SE3 | npt.ArrayLike,
    options: HelperArmOptions | None = None,
) -> InitialConditionResult:
    """A valid initial pose of the whole stack for an EE goal, by the helper arm (paper §III).

    See the module docstring for the algorithm. Plate 0 stays at ``am.home[0]``; plate n is
    put exactly at ``goal``; plates 1..n-1 at the arm's link midpoints (or near them, when
    the arm's closest pose had to be repaired).

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
    d_range = height_range(cfg)
    distance = math.hypot(*(goal_se3.translation - base.translation))  # no overflow for huge goals
    reach = reach_bound(cfg)
    if not distance <= reach:
        state = evaluate_state(am, am.home, goal=goal_se3, tolerance=opts.tolerance)
        message = (
            f"the goal is out of reach: {distance:.4g} m from the base, farther than the stack can span ({reach:.4g} m)"
        )
        logger.info("initial condition failed: %s", message)
        return InitialConditionResult(
            False, message, goal_se3, state, state.leg_lengths.copy(), None, None, 0, time.perf_counter() - t0
        )
    attempts = 0
    broken: list[str] = []  # attempts where the arm reached the goal but the plates were invalid
    closest, closest_error = "", math.inf
    last_q: np.ndarray | None = None
    last_points: np.ndarray | None = None
    # the arm's poses that did not give a valid stack, for the repair: (score, plates, q, d, points)
    candidates: list[tuple[float, list[pin.SE3], np.ndarray | None, float | None, np.ndarray | None]] = []

    def success(
        state: StackState, q: np.ndarray | None, d: float | None, points: np.ndarray | None, repaired: bool
    ) -> InitialConditionResult:
        dt = time.perf_counter() - t0
        if d is None:
            how = "repaired on the stack from the even screw pose (the arm's poses were not)"
        elif repaired:
            how = f"repaired on the stack from the helper arm's closest pose at link length d = {d:.4f} m"
        else:
            how = f"with link length d = {d:.4f} m"
        logger.info("initial condition found (%s) after %d attempt(s) in %.1f ms", how, attempts, 1e3 * dt)
        return InitialConditionResult(
            True,
            f"valid initial condition {how} after {attempts} attempt(s)"
            + ("" if state.feasible else f" (force limits exceeded: {len(state.violations)} violation(s))"),
            goal_se3,
            state,
            state.leg_lengths.copy(),
            None if q is None else q.copy(),
            d,
            attempts,
            dt,
            points,
            repaired,
        )

    for d_start in _d_scan(d0, distance, n, opts.d_step, d_range):
        if attempts >= opts.max_attempts:
            break
        tilt, twist = cluster_limits(cfg, d_start)
        if tilt <= 0.0 or twist <= 0.0:  # a level SP (nearly) cannot stand at this height
            continue
        attempts += 1
        arm = _cached_arm(cfg, round(d_start, 12))
        ik = arm.ik(
            goal_se3, base, regularization=opts.regularization, constraint_weight=opts.constraint_weight,
            tolerance=opts.arm_tolerance, restarts=opts.restarts,
            link_range=d_range if opts.free_link_length else None,
        )  # fmt: skip
        d = float(ik.link_length if ik.link_length is not None else d_start)
        last_q = ik.q
        plates, points = arm.forward(ik.q, base, d)
        last_points = points
        plates[n] = goal_se3.copy()
        if not ik.success:
            viol = float(arm.stack_violation(ik.q, 0.0, d).max())
            candidates.append((ik.position_error + ik.rotation_error + viol, plates, ik.q, d, points))
            if ik.position_error <= opts.arm_tolerance and ik.rotation_error <= opts.arm_tolerance:
                broken.append(f"d={d:.4f}: stack limits")
            elif ik.position_error + ik.rotation_error < closest_error:
                closest_error = ik.position_error + ik.rotation_error
                closest = f"closest: {ik.position_error:.3g} m, {ik.rotation_error:.3g} rad away at d = {d:.4f} m"
            logger.debug("initial condition: %s", ik.message)
            continue
        pa = PlateArrays.from_se3(plates)
        state, why = _kinematic_problems(am, pa, goal_se3, opts.tolerance)
        if state is None:
            broken.append(f"d={d:.4f}: {why}")
            candidates.append((0.0, plates, ik.q, d, points))
            logger.debug("initial condition at d=%.4f: kinematic violation(s) %s", d, why)
            continue
        return success(state, ik.q, d, points, False)

    candidates.sort(key=lambda c: c[0])
    repairs = candidates[: int(opts.repair_starts)]
    if opts.repair_starts > 0 and last_q is not None:
        # last: the plates evenly along the screw motion from the base to the goal
        screw = pin.log6(base.actInv(goal_se3))
        even = [base * pin.exp6(screw * (k / n)) for k in range(n + 1)]
        even[n] = goal_se3.copy()
        repairs.append((math.inf, even, None, None, None))
        # the even pose is often a saddle of the leg limits (every platform alike): also
        # repair it with its internal plates moved by seeded random twists
        repairs += [(math.inf, plates, None, None, None) for plates in perturbed_plates(even, opts.perturbed_starts)]
    for _, plates, q, d, points in repairs:
        pa, viol = repair_stack(am, plates)
        if viol > 0.0:
            logger.debug("repair from the pose at d=%s: %.3g left", d, viol)
            continue
        state, why = _kinematic_problems(am, pa, goal_se3, opts.tolerance)
        if state is not None:
            return success(state, q, d, points, True)
        logger.debug("repair from the pose at d=%s: %s", d, why)

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
    if repairs:
        why += (
            f"; repairing {len(repairs) - 1 - opts.perturbed_starts} of its closest pose(s), the even screw pose "
            f"and {opts.perturbed_starts} perturbed copies on the stack failed"
        )
    message = (
        f"no valid initial condition after {attempts} attempt(s) (d from {d0:.4f} m, then from "
        f"{min(max(distance / n, d_range[0]), d_range[1]):.4f} m, step {opts.d_step} m): {why}"
    )
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
