"""The optimization problem common to both methods: the chart, the constraint row families,
and the evaluation of a chart point.

Every iterate is evaluated by ONE closed-form pass: forces, lengths, deflection cosines, rise
and plate angles. Where the solver asks for derivatives at that point, a second pass gives
them. The passes run compiled (:class:`~assembler_pin.statics.pose_kernel.CompiledPass`, values
and derivatives in one call each), except in a problem that reads the sag or runs IPOPT, which
reads the intermediates of the numpy pass (:func:`~assembler_pin.statics.derivatives.pose_values`,
whose pass :func:`~assembler_pin.statics.derivatives.pose_derivatives` extends). The sag
objectives and the sag limit read the EE's linear sag of that pass (:func:`.sag.linear_sag`)
and, with the derivatives, its adjoint gradient
(:func:`~assembler_pin.compliance.loaded.sag_and_gradient`). The returned state is re-checked
by :func:`~assembler_pin.state.evaluate_state` in :mod:`.internal_poses`.
"""

from __future__ import annotations

from typing import cast

import numpy as np
import pinocchio as pin

from ..collision.check import Clearance, clearance
from ..collision.scene import Scene
from ..config.options import GEOMETRIC_MARGIN, SMOOTH_METHODS, OptimizeOptions
from ..exceptions import SingularConfigurationError, SingularIterateError
from ..kinematics import PlateArrays
from ..model.assembler import AssemblerModel
from ..statics.derivatives import PoseDerivatives, PoseValues, pose_derivatives, pose_values
from ..statics.pose_kernel import CompiledPass
from .charts import LocalChart, TaaChart
from .objective import SagObjective, motion_cost, omega, sag_reference
from .options import MotionTerm
from .point import ChartDerivatives, Point
from .rows import ClearanceRows, EETolerance, ForceLimitRows, LegLimitRows, MotionRows, SagRows
from .sag import linear_sag

__all__ = ["Problem", "finite_rows"]

#: What a non-finite constraint row (a degenerate trial point) is replaced by: infeasible.
_NON_FINITE_ROW = -1e6

#: How far inside the clearance [m] the clearance rows hold (beyond ``limit_margin``): SLSQP
#: honours its rows to ~1e-8 and the returned state is re-checked against the clearance itself.
CLEARANCE_MARGIN = 1e-6

#: The sag [m] standing in where none is defined (a singular trial point): finite, far
#: above any limit.
SINGULAR_SAG = 1e3


def finite_rows(rows: np.ndarray) -> np.ndarray:
    """``rows`` with NaN and -inf replaced by a large negative (infeasible) value, +inf by a
    large positive one: SLSQP cannot handle non-finite rows."""
    if np.isfinite(rows).all():  # the common case, without nan_to_num's copy
        return rows
    return np.nan_to_num(rows, nan=_NON_FINITE_ROW, posinf=-_NON_FINITE_ROW, neginf=_NON_FINITE_ROW)


class Problem:
    """The plates, the limits and the evaluation of chart points.

    Args:
        start: world poses of plates 0..n to start from.
        goal: the EE goal (plate n's reference pose).
        start_feasible: the start meets every constraint (then, for the smooth method and
            the force objective, both force limits are capped by its max|F|: max|F| never
            increases).
        motion: continuity with a previous sample (smooth method only).
        scene: obstacles and floor: with one (an empty scene too) the clearance rows
            (:class:`~.rows.ClearanceRows`) keep every checked pair apart; None: no such rows.
        start_clearance: the start's clearance in ``scene`` when the caller has it (measured
            here otherwise).
    """

    def __init__(
        self,
        am: AssemblerModel,
        start: PlateArrays,
        goal: pin.SE3,
        opts: OptimizeOptions,
        start_feasible: bool,
        motion: MotionTerm | None = None,
        scene: Scene | None = None,
        start_clearance: Clearance | None = None,
    ) -> None:
        self.am, self.opts, self.goal, self.motion, self.scene = am, opts, goal, motion, scene
        self.n = n = am.n
        free_ee = opts.ee_tolerance is not None
        ref = [start.se3(k) for k in range(n)] + [goal]
        movable = list(range(1, n)) + ([n] if free_ee else [])
        self.chart: LocalChart | TaaChart = (TaaChart if opts.method == "paper" else LocalChart)(ref, movable)
        self.nx_pose = self.chart.size
        leg = am.config.leg
        self.objective = SagObjective(
            opts.objective, opts.sag_weight, sag_reference(am) if opts.objective != "force" else 1.0
        )
        self.sag_rows = SagRows(opts.max_sag) if opts.max_sag is not None else None
        self.reads_sag = self.objective.needs_sag or self.sag_rows is not None
        # the sag and IPOPT's moment-variable form read the numpy pass's intermediates: a
        # problem that reads them keeps that pass
        numpy_pass = self.reads_sag or opts.method == "ipopt"
        self._compiled = None if numpy_pass else CompiledPass(am)
        start_values = self._compiled.values(start) if self._compiled is not None else pose_values(am, start)
        self.start_max_force = Point(np.zeros(0), start_values).max_abs_force
        force_objective = opts.objective == "force"
        cap = self.start_max_force if opts.method in SMOOTH_METHODS and start_feasible and force_objective else np.inf
        self.force_limits = ForceLimitRows(min(leg.max_tension, cap) - 1e-6, min(leg.max_compression, cap) - 1e-6)
        self.leg_limits = LegLimitRows(leg, opts.limit_margin, opts.rise_margin)
        self.ee = EETolerance(goal, opts.ee_tolerance, self.chart) if opts.ee_tolerance is not None else None
        self.motion_rows = MotionRows(motion, GEOMETRIC_MARGIN) if motion is not None else None
        margin = max(opts.limit_margin, 0.0) + CLEARANCE_MARGIN
        if scene is not None:
            near = start_clearance if start_clearance is not None else clearance(am, start, scene)
            self.clearance_rows: ClearanceRows | None = ClearanceRows(am, scene, margin, near)
        else:
            self.clearance_rows = None
        self._sag: tuple[Point, float] | None = None
        self._sag_grad: tuple[ChartDerivatives, np.ndarray] | None = None
        self.best: tuple[float, np.ndarray] | None = None
        self.evaluations = 0
        self.gradient_evaluations = 0
        self._point: Point | None = None
        self._point_key = b""
        self._derivs: tuple[bytes, ChartDerivatives] | None = None
        self._rows: tuple[Point, dict[str, np.ndarray]] | None = None

    def point(self, x_pose: np.ndarray) -> Point:
        """The values at the pose part of x (cached for the last point); tracks the best
        feasible point met."""
        x = np.array(x_pose, dtype=float)
        key = x.tobytes()
        if self._point is not None and self._point_key == key:
            return self._point
        plates = self.chart.plates(x)
        if self._compiled is not None:
            p = Point(x, self._compiled.values(plates))
        else:
            with np.errstate(invalid="ignore", divide="ignore"):
                p = Point(x, pose_values(self.am, plates))
        self._point, self._point_key = p, key
        self.evaluations += 1
        if self.feasible(p):
            value = self.score(p)
            if self.best is None or value < self.best[0]:
                self.best = (value, x.copy())
        return p

    def derivatives(self, x_pose: np.ndarray) -> ChartDerivatives:
        """Derivatives at the pose part of x, extending the point's closed-form pass.

        Raises:
            SingularIterateError: the statics are singular there (no derivative exists).
        """
        key = np.asarray(x_pose, dtype=float).tobytes()
        if self._derivs is not None and self._derivs[0] == key:
            return self._derivs[1]
        p = self.point(x_pose)
        if not isinstance(self.chart, LocalChart):
            raise TypeError("derivatives are taken in the local chart only (the paper's method has none)")
        if p.singular:
            raise SingularIterateError("the statics are singular at the iterate")
        try:
            pose = self._pose_derivatives(p)
        except (np.linalg.LinAlgError, SingularConfigurationError) as exc:
            raise SingularIterateError(str(exc)) from None
        # the block product for IPOPT (SLSQP keeps the dense one, its answers bit for bit)
        blocks = np.asarray(self.chart.movable) - 1 if self.opts.method == "ipopt" else None
        d = ChartDerivatives(pose, self.chart.twist_jacobian(p.x, p.plates), blocks)
        self._derivs = (key, d)
        self.gradient_evaluations += 1
        return d

    def _pose_derivatives(self, p: Point) -> PoseDerivatives:
        """The world-twist derivatives at the point, on the pass its values came from."""
        if self._compiled is not None:
            return self._compiled.derivatives(p.plates)
        return pose_derivatives(self.am, p.plates, _numpy_values(p))

    def score(self, p: Point) -> float:
        """The objective at the point (Ω, the sag or both, :mod:`assembler_pin.optimize.objective`),
        with the motion term."""
        omega_value = omega(p.max_abs_force, p.plate_angles, self.opts.w1, self.opts.w2)
        sag = self.sag(p) if self.objective.needs_sag else 0.0
        return self.objective.value(omega_value, sag) + motion_cost(p.lengths, self.motion)

    def sag(self, p: Point) -> float:
        """The EE's linear sag at the point [m] (:data:`SINGULAR_SAG` where it is not
        defined), computed once per point."""
        if self._sag is None or self._sag[0] is not p:
            sag = SINGULAR_SAG if p.singular else linear_sag(_numpy_values(p), float(self.am.config.leg.stiffness))[0]
            self._sag = (p, sag if np.isfinite(sag) else SINGULAR_SAG)
        return self._sag[1]

    def sag_gradient(self, x_pose: np.ndarray) -> np.ndarray:
        """(m,) the sag's gradient in chart coordinates [m per chart unit]: the adjoint
        gradient per world twist times the chart's ``B``, from the point's derivatives.

        Raises:
            SingularIterateError: the pose is singular there.
        """
        from ..compliance.loaded import sag_and_gradient  # delays scipy

        p, d = self.point(x_pose), self.derivatives(x_pose)
        if self._sag_grad is None or self._sag_grad[0] is not d:
            try:
                world = sag_and_gradient(self.am, p.plates, chart="world", derivatives=d.pose).gradient
            except (np.linalg.LinAlgError, SingularConfigurationError) as exc:
                raise SingularIterateError(str(exc)) from None
            self._sag_grad = (d, world @ d.B)
        return self._sag_grad[1]

    def rows(self, p: Point) -> dict[str, np.ndarray]:
        """The rows of every family at the point (>= 0 when it holds), computed once per
        point: ``leg``, ``force`` and, where they apply, ``ee``, ``motion``, ``sag`` and
        ``clearance``."""
        if self._rows is not None and self._rows[0] is p:
            return self._rows[1]
        rows = {"leg": self.leg_limits.values(p), "force": self.force_limits.values(p.forces)}
        if self.ee is not None:
            rows["ee"] = self.ee.values(p)
        if self.motion_rows is not None:
            rows["motion"] = self.motion_rows.values(p)
        if self.sag_rows is not None:
            rows["sag"] = self.sag_rows.values(self.sag(p))
        if self.clearance_rows is not None:
            rows["clearance"] = self.clearance_rows.values(p)
        self._rows = (p, rows)
        return rows

    def optional_rows(self, p: Point) -> list[np.ndarray]:
        """The EE-tolerance, motion, sag and clearance rows where they apply."""
        rows = self.rows(p)
        return [rows[k] for k in ("ee", "motion", "sag", "clearance") if k in rows]

    def feasible(self, p: Point) -> bool:
        """Every row of the problem holds at the point."""
        return all(bool((r >= 0).all()) for r in self.rows(p).values())


def _numpy_values(p: Point) -> PoseValues:
    """The numpy pass's values of a point of a problem off the compiled pass (every problem
    that reads the sag is): its intermediates feed the derivatives and the sag."""
    return cast(PoseValues, p.values)
