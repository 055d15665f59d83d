"""The helper arm model: Pinocchio FK of a 3n-DOF arm and its IK as a least-squares problem
(see the package docstring for the method; the arms are kept by :mod:`.cache`).

Frames: the arm's base is plate 0's world pose; poses are world poses. Units: metres, radians.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.naming import names
from ..config.options import HelperArmOptions
from ..config.schema import AssemblerConfig
from ..constraints import leg_limit_margins
from ..exceptions import OptionsError
from ..kinematics.legs import relative_leg_measures
from .limits import cached_leg_geometry, cluster_limits
from .urdf import helper_arm_urdf

__all__ = ["ArmIKProblem", "ArmIKResult", "HelperArm"]

logger = logging.getLogger(__name__)


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
        self.plate_frames = [self.model.getFrameId(names.plate(k)) for k in range(n + 1)]
        self.tip_frame = self.plate_frames[-1]
        self.cluster_joints = [self.model.getJointId(names.helper_joint(j, "x")) for j in range(n)]
        self.geometry = cached_leg_geometry(config)

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
        ([m], or [rad] for the deflection) so that a zero result keeps that far inside:
        the negated :func:`~assembler_pin.constraints.leg_limit_margins`, clipped at 0.

        Args:
            link_length: d [m] if not the arm's own.

        Returns:
            (5, n, 6) non-negative amounts, zero where the constraint holds.
        """
        d = self.link_length if link_length is None else float(link_length)
        return self.stack_violations(np.asarray(q, dtype=float).reshape(1, -1), margin, np.array([d]))[:, 0]

    def stack_violations(self, qs: np.ndarray, margin: float, link_lengths: np.ndarray) -> np.ndarray:
        """:meth:`stack_violation` of m arm poses at once (the single pose is the case m = 1).

        Args:
            qs: (m, 3n) joint angles [rad]; link_lengths: (m,) d of each [m].

        Returns:
            (5, m, n, 6) non-negative amounts, zero where the constraint holds.
        """
        m = qs.shape[0]
        rot = _xyz_rotations(qs.reshape(-1, 3)).reshape(m, -1, 3, 3)
        half = np.zeros((m, 1, 3, 1))
        half[:, 0, 2, 0] = 0.5 * np.asarray(link_lengths, dtype=float)
        translations = (half + rot @ half)[..., 0]
        lengths, cos, rise = relative_leg_measures(self.geometry, rot, translations)
        return np.maximum(-leg_limit_margins(self.config.leg, lengths, cos, rise, margin), 0.0)

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
        once (3 poses, one more for d), all evaluated in one :meth:`stack_violations` call."""
        n = self.config.platforms
        flat = base_value.reshape(5, n, 6)
        d = self.link_length if link_length is None else float(link_length)
        qs = np.repeat(q[None, :], 4 if with_d else 3, axis=0)
        for k in range(3):
            qs[k, k::3] += step
        ds = np.full(qs.shape[0], d)
        if with_d:
            ds[3] += step
        moved = self.stack_violations(qs, margin, ds)  # (5, 3 or 4, n, 6), one call
        jac: np.ndarray = np.zeros((5, n, 6, n, 3))
        for k in range(3):
            diff = (moved[:, k] - flat) / step  # (5, n, 6)
            jac[:, np.arange(n), :, np.arange(n), k] = diff.transpose(1, 0, 2)
        jac = jac.reshape(30 * n, 3 * n)
        if not with_d:
            return jac
        col = (moved[:, 3] - flat).reshape(-1, 1) / step
        return np.hstack([jac, col])

    def ik(
        self,
        goal: pin.SE3,
        base: pin.SE3 | None = None,
        q0: npt.ArrayLike | None = None,
        options: HelperArmOptions | None = None,
        margin: float = 1e-5,
        seed: int = 0,
        link_range: tuple[float, float] | None = None,
    ) -> ArmIKResult:
        """Joint angles (and, optionally, the link length) that put the tip at ``goal``,
        within the joint limits and, as far as possible, with the plates a valid pose of the
        stack.

        Bounded least squares (``trf``, bounds = joint limits) on the residual of an
        :class:`ArmIKProblem`, ``[log6(goal⁻¹·tip(q)), c·v(q), w·q]``, with the analytic
        Jacobian ``Jlog6·J_tip`` (Pinocchio, LOCAL frame) for the goal error. ``v(q)`` is
        :meth:`stack_violation` (the stack's leg constraints as a penalty, so the solve is
        constrained by them as well as by the joint limits; forward differences), and the
        pull ``w·q`` spreads the bending evenly over the clusters. A second solve without
        the pull then reaches the goal exactly.

        With ``link_range`` the link length d is a variable too, bounded to that range and
        started at the arm's own d: the tip's translation is ``(d/d_arm)·p_tip(q)`` and its
        rotation does not depend on d, so the tip twist per unit d is
        ``[R_tipᵀ·p_tip/d_arm, 0]`` (LOCAL frame) and the LOCAL Jacobian's linear rows scale
        by ``d/d_arm``. This removes the singularity of changing a straight arm's length.

        Starts: ``q0`` (default 0), then ``options.restarts`` deterministic random points within
        half the limits (with d at the arm's own). Stops at the first start that succeeds.

        Args:
            goal: world pose of the tip (the EE) [m, rad].
            base: world pose of plate 0 (default identity).
            options: w = ``regularization`` [m/rad], c = ``constraint_weight``,
                ``arm_tolerance`` (largest |log6| error, translation [m] and rotation [rad]
                parts, to count as reached) and ``restarts`` (default :class:`HelperArmOptions`).
            margin: distance kept from the stack's bounds [m or rad].
            seed: seed of the restart points.
            link_range: (lowest, highest) link length d [m] when d is a variable.

        Returns:
            An :class:`ArmIKResult`; ``success`` needs the goal reached *and* the stack's
            leg constraints met (:meth:`stack_violation` zero); ``link_length`` is the d used.
        """
        opts = options or HelperArmOptions()
        base = pin.SE3.Identity() if base is None else base
        problem = ArmIKProblem(self, (base.actInv(goal)).inverse(), opts.constraint_weight, margin, link_range)
        rng = np.random.default_rng(seed)
        starts = [np.zeros(self.nq) if q0 is None else np.asarray(q0, dtype=float)]
        starts += [rng.uniform(0.5 * self.lower, 0.5 * self.upper) for _ in range(opts.restarts)]
        best: tuple[float, np.ndarray, float, float, float, float] | None = None
        for k, start in enumerate(starts):
            q, d, pos, rot, viol = _solve_from(problem, start, opts)
            if best is None or pos + rot + viol < best[0]:
                best = (pos + rot + viol, q, d, pos, rot, viol)
            if pos <= opts.arm_tolerance and rot <= opts.arm_tolerance and viol == 0.0:
                return ArmIKResult(True, q, pos, rot, problem.evaluations, k + 1, "reached", d)
        assert best is not None
        return _unreached(problem, best[1:], opts, len(starts))


def _solve_from(
    problem: ArmIKProblem, start: np.ndarray, opts: HelperArmOptions
) -> tuple[np.ndarray, float, float, float, float]:
    """One start of :meth:`HelperArm.ik`: the solve with the pull (when ``regularization`` > 0),
    then without; returns q [rad], d [m] and the position [m], rotation [rad] and leg errors."""
    x = problem.start(start)
    x = problem.solve(x, opts.regularization, True) if opts.regularization > 0 else x
    x = problem.solve(x, 0.0, False)
    q, d = problem.split(x)
    pos, rot, viol = problem.errors(q, d)
    return q, d, pos, rot, viol


def _unreached(
    problem: ArmIKProblem, best: tuple[np.ndarray, float, float, float, float], opts: HelperArmOptions, starts: int
) -> ArmIKResult:
    """The failed :class:`ArmIKResult` of the closest start ``best`` (q, d, position,
    rotation and leg errors), saying whether the goal or the stack's limits were missed."""
    q, d, pos, rot, viol = best
    logger.debug("arm IK failed; least_squares statuses %s", problem.statuses)
    if pos <= opts.arm_tolerance and rot <= opts.arm_tolerance:
        why = f"reaches the goal only with plates past the stack's limits (by up to {viol:.3g})"
    else:
        why = f"cannot reach the goal within its joint limits: closest {pos:.3g} m, {rot:.3g} rad away"
    message = f"the helper arm (d = {d:.4f} m) {why}"
    return ArmIKResult(False, q, pos, rot, problem.evaluations, starts, message, d)


class ArmIKProblem:
    """One IK problem of the helper arm: residual and Jacobian of x = q (and d when the link
    length is free), for ``scipy.optimize.least_squares``; counts its evaluations.

    Residual ``[log6(goal⁻¹·tip), c·v(q, d), w·x]``: the goal error [m, rad], the stack's leg
    constraint violations weighted by c (:meth:`HelperArm.stack_violation`) and the pull
    toward zero (only while ``w > 0``, d not pulled). Pinocchio calls:
    ``framesForwardKinematics`` per residual, ``computeJointJacobians`` +
    ``getFrameJacobian`` (LOCAL) per Jacobian, on the arm's own data.
    """

    def __init__(
        self,
        arm: HelperArm,
        goal_inv: pin.SE3,
        constraint_weight: float,
        margin: float,
        link_range: tuple[float, float] | None,
    ) -> None:
        self.arm, self.goal_inv = arm, goal_inv
        self.constraint_weight, self.margin = constraint_weight, margin
        self.free_d = link_range is not None
        self.lower, self.upper = arm.lower, arm.upper
        if link_range is not None:
            d_lo, d_hi = float(min(link_range)), float(max(link_range))
            if not d_lo <= arm.link_length <= d_hi:
                raise OptionsError(f"link_range {link_range!r} must contain the arm's link length {arm.link_length}")
            self.lower, self.upper = np.append(self.lower, d_lo), np.append(self.upper, d_hi)
        self.evaluations = 0
        self.statuses: list[int] = []
        self._last_violation: tuple[np.ndarray, np.ndarray] | None = None  # (x, violation at x)

    def _violation(self, x: np.ndarray) -> np.ndarray:
        """:meth:`HelperArm.stack_violation` at x, kept for the last x (the Jacobian is asked
        at the point whose residual was just computed)."""
        if self._last_violation is not None and np.array_equal(self._last_violation[0], x):
            return self._last_violation[1]
        q, d = self.split(x)
        value = self.arm.stack_violation(q, self.margin, d)
        self._last_violation = (np.array(x, dtype=float), value)
        return value

    def start(self, q: np.ndarray) -> np.ndarray:
        return np.append(q, self.arm.link_length) if self.free_d else q

    def split(self, x: np.ndarray) -> tuple[np.ndarray, float]:
        n_q = self.arm.nq
        return (x[:n_q], float(x[n_q])) if self.free_d else (x, self.arm.link_length)

    def _pull(self, w: float) -> np.ndarray:
        n_q = self.arm.nq
        return np.diag(np.append(np.full(n_q, w), 0.0) if self.free_d else np.full(n_q, w))

    def residual(self, x: np.ndarray, w: float) -> np.ndarray:
        self.evaluations += 1
        q, d = self.split(x)
        err, _ = self.arm._error(q, self.goal_inv, d / self.arm.link_length)
        parts = [err, self.constraint_weight * self._violation(x).ravel()]
        if w > 0:
            parts.append(self._pull(w) @ x)
        return np.concatenate(parts)

    def jacobian(self, x: np.ndarray, w: float) -> np.ndarray:
        arm = self.arm
        q, d = self.split(x)
        scale = d / arm.link_length
        _, m = arm._error(q, self.goal_inv, scale)
        pin.computeJointJacobians(arm.model, arm.data, q)
        j_tip = pin.getFrameJacobian(arm.model, arm.data, arm.tip_frame, pin.LOCAL)
        if self.free_d:
            tip = arm.data.oMf[arm.tip_frame]
            j_d = np.concatenate([tip.rotation.T @ tip.translation / arm.link_length, np.zeros(3)])
            j_tip = np.hstack([np.vstack([scale * j_tip[:3], j_tip[3:]]), j_d[:, None]])
        j_pen = arm._penalty_jacobian(q, self._violation(x), self.margin, link_length=d, with_d=self.free_d)
        parts = [pin.Jlog6(m) @ j_tip, self.constraint_weight * j_pen]
        if w > 0:
            parts.append(self._pull(w))
        return np.vstack(parts)

    def solve(self, start: np.ndarray, w: float, loose: bool) -> np.ndarray:
        """One bounded least-squares solve from ``start``; the pulled (``loose``) solve only
        has to land near the spread-out solution, the exact one polishes it."""
        from scipy.optimize import least_squares  # on first use: fast start-up

        tol = 1e-6 if loose else 1e-15
        res = least_squares(
            self.residual,
            np.clip(start, self.lower, self.upper),
            jac=self.jacobian,
            args=(w,),
            bounds=(self.lower, self.upper),
            method="trf",
            ftol=tol,
            xtol=tol,
            gtol=tol,
            max_nfev=60 if loose else 100,
        )
        self.statuses.append(int(res.status))
        return res.x

    def errors(self, q: np.ndarray, d: float) -> tuple[float, float, float]:
        """(position error [m], rotation error [rad], largest leg violation) at (q, d)."""
        err, _ = self.arm._error(q, self.goal_inv, d / self.arm.link_length)
        viol = float(self.arm.stack_violation(q, 0.0, d).max())
        return float(np.linalg.norm(err[:3])), float(np.linalg.norm(err[3:])), viol


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
