"""The moment-variable form of the epigraph problem, for IPOPT: a banded constraint Jacobian.

In :mod:`.smooth`'s form, platform j's forces depend on every plate above it (through the
moment of the weight it carries, ``M_up,j``), so the force rows of the Jacobian are a
triangle: at n = 64, 87 % of its 173,000 non-zeros, and a dense block in IPOPT's KKT factor.
Here the moments are variables, ``x = [poses in the local chart, m_0..m_{n-1}, s]`` with
``m_j`` [N·m] (held in x in units of :data:`MOMENT_SCALE`) standing for ``M_up,j`` (about
the world origin), tied to the poses by the
equality rows of the level above (:func:`assembler_pin.statics.closed_form.equilibrium`'s
``level_moment``):

    ``m_j - m_{j+1} - level_{j+1}(plates j+1, j+2) = 0``   (``m_n = 0``)

Platform j's forces ``F_j = K_j⁻¹ (rhs_j - M_up,j + m_j) + m_s g·u`` then read plates j and
j+1 and ``m_j`` only: a force row has 12 pose columns, 3 moment columns and ``s``, a level
row 12 pose columns and 2 moment columns; O(n) non-zeros (37,000 at n = 64) and a banded
KKT factor. Where the equality rows hold, the
forces, rows and objective are those of :mod:`.smooth` exactly; at the optimum IPOPT meets
them to its constraint tolerance (the answer is re-checked on the poses alone, by the
Pinocchio statics in :mod:`.internal_poses`).

Every point evaluated goes through :meth:`~.problem.Problem.point` (the true forces of
the poses), which keeps the best feasible point met.

The derivatives are the closed form's (:mod:`assembler_pin.statics.derivatives`) restricted to each
platform's two plates (:func:`banded_derivatives`, world twists ``[η_j, η_{j+1}]``), then
taken to the chart by the 6×6 blocks of the local chart.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np

from ..common.linalg import inverse_or_nan, skew
from ..exceptions import SingularIterateError
from ..model.assembler import AssemblerModel
from ..statics.derivatives import (
    PoseValues,
    axial_force_derivatives,
    plate_angle_sq_derivatives,
    rest_directions,
    transverse_force_derivatives,
)
from .charts import LocalChart
from .objective import deviation_term_gradient, motion_cost_gradient
from .point import Point, block_chart
from .problem import Problem, finite_rows
from .smooth import SmoothForm

__all__ = ["MOMENT_SCALE", "BandedDerivatives", "WrenchForm", "banded_derivatives", "level_moments"]

_I3 = np.eye(3)

#: The unit of the moment variables and of the level rows [N·m]: x holds ``m_j / MOMENT_SCALE``.
#: Measured on the bench's long stacks (n = 16 / 32 / 64, iterations): 1 N·m stalls IPOPT's
#: quasi-Newton Hessian (200, the cap, at every size); 30 / 100 / 300 N·m give 68–120
#: iterations, 100 the fewest over the three sizes.
MOMENT_SCALE = 100.0


@dataclass(frozen=True)
class BandedDerivatives:
    """The derivatives of platform j's quantities w.r.t. the world twists of its two plates,
    last axis 12 = ``[η_j, η_{j+1}]`` (each ``(v, ω)``), and of the level equality rows.

    Attributes:
        d_forces: (n, 6, 12) of the actuator forces [N] at the moment variables;
            d_forces_dm (n, 6, 3) [N per N·m], w.r.t. ``m_j``.
        d_lengths: (n, 6, 12); d_cos_deflection: (n, 6, 2, 12); d_rise: (n, 6, 12).
        d_level: (n, 3, 12) [N·m] the moment of level j+1 (plate j+1, the legs of platform
            j+1, the payload at j+1 = n) w.r.t. ``[η_{j+1}, η_{j+2}]``.
    """

    d_forces: np.ndarray
    d_forces_dm: np.ndarray
    d_lengths: np.ndarray
    d_cos_deflection: np.ndarray
    d_rise: np.ndarray
    d_level: np.ndarray


def _point_blocks(points: np.ndarray) -> np.ndarray:
    """d(point)/d(world twist of its plate), ``[I, -[x]×]``: (..., 3) → (..., 3, 6)."""
    out = np.empty((*points.shape, 6))
    out[..., :3] = _I3
    out[..., 3:] = -skew(points)
    return out


def _forces_at_moments(am: AssemblerModel, v: PoseValues, m: np.ndarray, K_inv: np.ndarray) -> np.ndarray:
    """(n, 6) actuator forces [N] with ``m`` (n, 3) [N·m] in place of the moments above
    each platform: the closed form's, moved by ``K⁻¹ [0; m - M_up]`` (equal where they agree)."""
    eq = v.eq
    a = eq.a + np.einsum("jab,jb->ja", K_inv[..., 3:], m - eq.up_moment)
    return a + am.config.leg.shaft_mass * eq.gu


def banded_derivatives(am: AssemblerModel, v: PoseValues, m: np.ndarray) -> BandedDerivatives:
    """Every derivative of the moment-variable form at the moment variables ``m`` (n, 3)
    [N·m], per platform (:class:`BandedDerivatives`).

    The same equilibrium as :func:`~assembler_pin.statics.derivatives.pose_derivatives` with
    ``M_up,j`` replaced by ``m_j``: ``K da = d(rhs) - dK a`` on the platform's own plates.
    """
    cfg, n = am.config, am.n
    leg = cfg.leg
    g = np.array([0.0, 0.0, -cfg.gravity])
    eq, R = v.eq, v.plates.R
    K_inv = inverse_or_nan(eq.K)
    a = _forces_at_moments(am, v, m, K_inv) - leg.shaft_mass * eq.gu
    db = np.zeros((n, 6, 3, 12))
    dt = np.zeros((n, 6, 3, 12))
    db[..., :6] = _point_blocks(eq.b)
    dt[..., 6:] = _point_blocks(eq.t)
    dd = dt - db
    u, L = eq.u, eq.L
    dL = np.einsum("jik,jikc->jic", u, dd)
    du = (dd - u[..., None] * dL[:, :, None, :]) / L[..., None, None]
    # the closed form's own derivative steps, on the platform's 12 columns with m_j held
    dgu, df_perp = transverse_force_derivatives(am, eq, dL, du)
    da = axial_force_derivatives(eq, dt, du, df_perp, np.zeros((n, 3, 12)), a)
    d_forces = da + leg.shaft_mass * dgu
    # leg rows (gradients._deflection_and_rise_derivatives, on 12 columns)
    h_bottom, h_top = rest_directions(am.geometry.home_direction, R)
    d_cos_b = np.einsum("jik,jikc->jic", h_bottom, du)
    d_cos_t = np.einsum("jik,jikc->jic", h_top, du)
    d_cos_b[..., 3:6] += np.cross(h_bottom, u)
    d_cos_t[..., 9:12] += np.cross(h_top, u)
    z_bottom = R[:-1, :, 2]
    d_rise = np.einsum("jk,jikc->jic", z_bottom, dd)
    d_rise[..., 3:6] += np.cross(z_bottom[:, None, :], eq.d)
    # the level moments: plate k, the legs of platform k, the payload (closed_form._weight_above)
    skew_g = skew(g)
    d_legs = -np.matmul(
        skew_g, (leg.motor_mass * (db + leg.motor_com * du) + leg.shaft_mass * (dt - leg.shaft_com * du)).sum(axis=1)
    )  # (n, 3, 12): platform k's legs on [η_k, η_{k+1}]
    d_level = np.zeros((n, 3, 12))
    d_level[..., :6] = -cfg.plate.mass * np.matmul(skew_g, _point_blocks(v.plates.p[1:]))
    d_level[:-1] += d_legs[1:]
    d_level[-1, :, :6] += -cfg.payload.mass * skew_g @ _point_blocks(eq.payload_point)
    return BandedDerivatives(
        d_forces=d_forces,
        d_forces_dm=K_inv[..., 3:],
        d_lengths=dL,
        d_cos_deflection=np.stack([d_cos_b, d_cos_t], axis=2),
        d_rise=d_rise,
        d_level=d_level,
    )


def level_moments(am: AssemblerModel, v: PoseValues) -> np.ndarray:
    """(n, 3) [N·m] the moment about the world origin of level j+1 alone (plate j+1, the
    legs of platform j+1, the payload at j+1 = n): ``M_up,j - M_up,j+1``."""
    up = v.eq.up_moment
    return up - np.concatenate([up[1:], np.zeros((1, 3))])


class _Blocks:
    """The chart columns of rows that read two consecutive plates: for rows of platform j,
    the columns of plates ``first[j]`` and ``first[j] + 1`` (-1 where a plate is fixed), and
    the 6×6 chart blocks that take world twists to chart coordinates."""

    def __init__(self, chart: LocalChart) -> None:
        self.n = chart.n
        self.slot = np.full(self.n + 2, -1)
        self.slot[chart.movable] = np.arange(len(chart.movable))

    def cols(self, first: np.ndarray) -> np.ndarray:
        """(len(first), 12) chart columns of ``[plate first, plate first + 1]``."""
        slots = self.slot[np.stack([first, first + 1], axis=1)]  # (r, 2)
        cols = 6 * slots[:, :, None] + np.arange(6)
        return np.where(slots[:, :, None] >= 0, cols, -1).reshape(-1, 12)

    def to_chart(self, d: np.ndarray, first: np.ndarray, B: np.ndarray) -> np.ndarray:
        """``d`` (r, ..., 12) per world twist → per chart coordinate of the same columns,
        with the 6×6 blocks ``B`` (n+2, 6, 6) of plates 0..n+1 (zero where fixed)."""
        blocks = B[np.stack([first, first + 1], axis=1)]  # (r, 2, 6, 6)
        shape = d.shape
        d2 = d.reshape(shape[0], -1, 2, 6)
        out = np.einsum("rqbk,rbkc->rqbc", d2, blocks)
        return out.reshape(shape)


class WrenchForm:
    """The moment-variable epigraph problem (module docstring): values, rows, bounds and the
    sparse Jacobian of the rows, for :func:`~.ipopt.run_ipopt`.

    Rows (``cons``, in order): ``s ∓ F`` (2·6n), the force limits (one row on ``s``, or 2·6n
    on the forces), the leg rows (5·6n), the EE tolerance (2), the motion step (2·6n), the
    sag limit (1) — all ``>= 0`` — then the level equalities (3n, ``= 0``).
    """

    def __init__(self, problem: Problem) -> None:
        if not isinstance(problem.chart, LocalChart):
            raise TypeError("the moment-variable form is taken in the local chart")
        self.problem, self.chart = problem, problem.chart
        n = self.n = problem.n
        self.nx_pose = problem.nx_pose
        self.nx = self.nx_pose + 3 * n + 1
        self.blocks = _Blocks(problem.chart)
        self.smooth = SmoothForm(problem)
        self.singular = ""
        self.interrupt: KeyboardInterrupt | None = None
        self._last: tuple[bytes, np.ndarray, np.ndarray] | None = None
        self._build_pattern()

    # --- the variables -------------------------------------------------------------------

    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """(pose part, moments (n, 3) [N·m], s)."""
        return x[: self.nx_pose], MOMENT_SCALE * x[self.nx_pose : -1].reshape(self.n, 3), float(x[-1])

    def x0(self, x0_smooth: np.ndarray) -> np.ndarray:
        """The start from :meth:`.smooth.SmoothForm.x0`'s ``[poses, s]``: the moments of the
        start poses, so that the equality rows hold there."""
        v = self._values(x0_smooth[:-1])
        return np.concatenate([x0_smooth[:-1], v.eq.up_moment.ravel() / MOMENT_SCALE, x0_smooth[-1:]])

    def smooth_x(self, x: np.ndarray) -> np.ndarray:
        """``[poses, s]``: the point of :mod:`.smooth`'s form."""
        return np.append(x[: self.nx_pose], x[-1])

    def _values(self, x_pose: np.ndarray) -> PoseValues:
        """The numpy pass's values at the pose part (IPOPT's problem never runs compiled)."""
        return cast(PoseValues, self.problem.point(x_pose).values)

    # --- values --------------------------------------------------------------------------

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) bounds of :meth:`cons`: ``[0, inf)`` for the inequality rows, 0 for
        the equalities."""
        lower = np.zeros(self.shape[0])
        upper = np.full(self.shape[0], np.inf)
        upper[-3 * self.n :] = 0.0
        return lower, upper

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, variables)."""
        return self.ng, self.nx

    def fun(self, x: np.ndarray) -> float:
        """The objective: :meth:`.smooth.SmoothForm.fun` (it reads no moment variable)."""
        return self.smooth.fun(self.smooth_x(x))

    def cons(self, x: np.ndarray) -> np.ndarray:
        """Every row (class docstring), inequalities ``>= 0`` then equalities ``= 0``."""
        pr = self.problem
        x_pose, m, s = self.split(x)
        p = pr.point(x_pose)
        v = self._values(x_pose)
        with np.errstate(invalid="ignore"):
            F = _forces_at_moments(pr.am, v, m, inverse_or_nan(v.eq.K))
        limits = pr.force_limits.epigraph_values(F, s)
        levels = (m - np.concatenate([m[1:], np.zeros((1, 3))]) - level_moments(pr.am, v)) / MOMENT_SCALE
        rows = [self.smooth.epigraph.values(F, s), limits, pr.rows(p)["leg"], *pr.optional_rows(p), levels.ravel()]
        return finite_rows(np.concatenate(rows))

    # --- the sparse Jacobian -------------------------------------------------------------

    def _build_pattern(self) -> None:
        """The row and column of every structural non-zero, in the order :meth:`_entries`
        fills them, and the permutation to CasADi's column-major order."""
        pr, n = self.problem, self.n
        nxp = self.nx_pose
        j6 = np.repeat(np.arange(n), 6)  # platform of each force / leg row
        pose_cols = self.blocks.cols(j6)  # (6n, 12)
        m_cols = nxp + 3 * j6[:, None] + np.arange(3)  # (6n, 3)
        s_col = self.nx - 1
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        self._families: list[tuple[str, int]] = []
        row = 0

        def add(kind: str, count: int, c: np.ndarray) -> None:
            nonlocal row
            r = np.broadcast_to((row + np.arange(count))[:, None], c.shape)
            rows.append(r.ravel())
            cols.append(c.ravel())
            self._families.append((kind, count))
            row += count

        force_cols = np.hstack([pose_cols, m_cols, np.full((6 * n, 1), s_col)])
        add("s-F", 6 * n, force_cols)
        add("s+F", 6 * n, force_cols)
        if pr.force_limits.symmetric:
            add("limit-s", 1, np.array([[s_col]]))
        else:
            add("-F", 6 * n, force_cols[:, :-1])
            add("+F", 6 * n, force_cols[:, :-1])
        for kind in ("L", "-L", "cos_b", "cos_t", "rise"):
            add(kind, 6 * n, pose_cols)
        if pr.ee is not None:
            add("ee", 2, np.broadcast_to(np.arange(nxp - 6, nxp), (2, 6)))
        if pr.motion_rows is not None:
            add("-L", 6 * n, pose_cols)
            add("L", 6 * n, pose_cols)
        if pr.sag_rows is not None:
            add("sag", 1, np.arange(nxp)[None, :])
        j3 = np.repeat(np.arange(n), 3)  # level row 3j + c reads m_j[c] and m_{j+1}[c]
        m_self = (nxp + np.arange(3 * n))[:, None]
        m_next = np.where(j3[:, None] < n - 1, m_self + 3, -1)
        add("level", 3 * n, np.hstack([self.blocks.cols(j3 + 1), m_self, m_next]))
        r, c = np.concatenate(rows), np.concatenate(cols)
        self._keep = c >= 0
        r, c = r[self._keep], c[self._keep]
        self.ng = row
        self._order = np.lexsort((r, c))  # column-major, as CasADi stores non-zeros
        self.rows, self.cols = r[self._order], c[self._order]

    def _chart_blocks(self, x_pose: np.ndarray, v: PoseValues) -> np.ndarray:
        """(n+2, 6, 6) the chart's blocks per plate 0..n+1 (zero for a fixed plate)."""
        out = np.zeros((self.n + 2, 6, 6))
        out[self.chart.movable] = self.chart.twist_blocks(x_pose, v.plates)
        return out

    def _entries(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(objective gradient (nx,), Jacobian non-zeros in :attr:`rows`/:attr:`cols` order)."""
        pr, n = self.problem, self.n
        x_pose, m, _ = self.split(x)
        p = pr.point(x_pose)
        if p.singular:
            raise SingularIterateError("the statics are singular at the iterate")
        v = self._values(x_pose)
        bd = banded_derivatives(pr.am, v, m)
        B = self._chart_blocks(x_pose, v)
        j6 = np.repeat(np.arange(n), 6)
        to_chart = self.blocks.to_chart
        dF = to_chart(bd.d_forces.reshape(6 * n, 12), j6, B)
        dFm = MOMENT_SCALE * bd.d_forces_dm.reshape(6 * n, 3)
        dL = to_chart(bd.d_lengths.reshape(6 * n, 12), j6, B)
        per_kind = {
            "s-F": np.hstack([-dF, -dFm, np.ones((6 * n, 1))]),
            "s+F": np.hstack([dF, dFm, np.ones((6 * n, 1))]),
            "limit-s": np.array([[-1.0]]),
            "-F": np.hstack([-dF, -dFm]),
            "+F": np.hstack([dF, dFm]),
            "L": dL,
            "-L": -dL,
            "cos_b": to_chart(bd.d_cos_deflection[:, :, 0].reshape(6 * n, 12), j6, B),
            "cos_t": to_chart(bd.d_cos_deflection[:, :, 1].reshape(6 * n, 12), j6, B),
            "rise": to_chart(bd.d_rise.reshape(6 * n, 12), j6, B),
        }
        if pr.ee is not None:
            # the EE is the last movable plate: its block of B, on the last six columns
            B_ee = np.zeros((6, self.nx_pose))
            B_ee[:, -6:] = B[self.n]
            per_kind["ee"] = pr.ee.jacobian(p, B_ee)[:, -6:]
        if pr.sag_rows is not None:
            per_kind["sag"] = pr.sag_rows.jacobian(pr.sag_gradient(x_pose))
        j3 = np.repeat(np.arange(n), 3)
        d_level = to_chart(bd.d_level.reshape(3 * n, 12), j3 + 1, B) / MOMENT_SCALE
        per_kind["level"] = np.hstack([-d_level, np.ones((3 * n, 1)), -np.ones((3 * n, 1))])
        values = np.concatenate([per_kind[kind].ravel() for kind, _ in self._families])
        jac = values[self._keep][self._order]
        return self._gradient(x_pose, p, v, dL, B), jac

    def _gradient(self, x_pose: np.ndarray, p: Point, v: PoseValues, dL: np.ndarray, B: np.ndarray) -> np.ndarray:
        """The objective's gradient (nx,): on the poses and ``s`` (none on the moments)."""
        pr, n = self.problem, self.n
        movable = np.asarray(self.chart.movable)
        d_ang = plate_angle_sq_derivatives(v.deviation, v.plates.p)  # (n, 6n) world twists
        d_omega = pr.opts.w2 * deviation_term_gradient(p.plate_angles, block_chart(d_ang, B[movable], movable - 1))
        d_sag = pr.sag_gradient(x_pose) if pr.objective.needs_sag else None
        grad = pr.objective.gradient(np.append(d_omega, pr.opts.w1), None if d_sag is None else np.append(d_sag, 0.0))
        if pr.motion is not None:
            grad[:-1] += motion_cost_gradient(p.lengths, self._dense(dL, np.repeat(np.arange(n), 6)), pr.motion)
        out = np.zeros(self.nx)
        out[: self.nx_pose] = grad[:-1]
        out[-1] = grad[-1]
        return out

    def _dense(self, d: np.ndarray, first: np.ndarray) -> np.ndarray:
        """Rows ``d`` (r, 12) on the chart columns of plates ``first``, ``first + 1`` as
        dense rows (r, nx_pose)."""
        cols = self.blocks.cols(first)
        keep = cols >= 0
        dense = np.zeros((d.shape[0], self.nx_pose))
        dense[np.broadcast_to(np.arange(d.shape[0])[:, None], cols.shape)[keep], cols[keep]] = d[keep]
        return dense

    def derivatives(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(objective gradient, Jacobian non-zeros) at ``x``, computed once per point; NaN at
        a singular iterate, whose reason is kept in :attr:`singular`."""
        key = x.tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1], self._last[2]
        try:
            grad, nz = self._entries(x)
        except (SingularIterateError, np.linalg.LinAlgError) as exc:
            self.singular = f"stopped at a singular iterate: {exc}"
            grad, nz = np.full(x.size, np.nan), np.full(self.rows.size, np.nan)
        self._last = (key, grad, nz)
        return grad, nz
