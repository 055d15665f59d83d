"""The closed-form statics as plain loops: the one source of the compiled kernel and of the
pure-Python path.

The equilibrium is the one of :func:`~assembler_pin.statics.closed_form.equilibrium` (each leg
balances its own weight; the top plate of each platform the weight above it and the six
ball forces; module docstring of :mod:`assembler_pin.statics.closed_form`). The loops below use only
scalar arithmetic, :mod:`math` and ``x[i, j, ...]`` indexing, so the same code runs

* compiled by numba on numpy arrays (:mod:`~assembler_pin.statics.kernel` compiles copies
  of these functions whose callees are the compiled ones), and
* interpreted on :class:`Grid` containers, without numpy (:func:`closed_form_pure`): the
  home pose of ``assembler-pin statics --home`` is answered this way, without loading
  numpy's and Pinocchio's libraries.

Frames: world poses of plates 0..n; forces [N], tension positive.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..config.schema import AssemblerConfig

__all__ = ["CONSTANT_NAMES", "Grid", "closed_form_pure", "constants"]

#: The order of ``consts``: gravity [m/s²], motor mass [kg], shaft mass [kg], motor CoM
#: from the bottom joint [m], shaft CoM from the top joint [m], plate mass [kg], payload
#: mass [kg], payload offset along the top plate's z [m].
CONSTANT_NAMES = ("gravity", "motor_mass", "shaft_mass", "motor_com", "shaft_com", "plate_mass", "payload", "offset")


def constants(cfg: AssemblerConfig) -> tuple[float, ...]:
    """The constants of a configuration in the order of :data:`CONSTANT_NAMES`."""
    leg = cfg.leg
    return (
        cfg.gravity,
        leg.motor_mass,
        leg.shaft_mass,
        leg.motor_com,
        leg.shaft_com,
        cfg.plate.mass,
        cfg.payload.mass,
        cfg.payload.offset,
    )


def _legs_py(R, p, bottom, top, consts, s, t, u, fp, gu, lev_f, lev_m):
    """Stack ``s``: top joints t, leg directions u, transverse ball forces fp, gravity along
    the legs gu (n, 6, ...), and each level's weight lev_f [N, downward] and its moment's
    x, y about the world origin lev_m (level k: plate k (k ≥ 1), the legs of SP k, the payload)."""
    g, mm, ms, mc = consts[0], consts[1], consts[2], consts[3]
    sc, mplate, mpay, off = consts[4], consts[5], consts[6], consts[7]
    lever, w_plate, w_leg = mc * mm - sc * ms, mplate * g, (mm + ms) * g
    n = R.shape[1] - 1
    lev_f[0], lev_m[0, 0], lev_m[0, 1] = 0.0, 0.0, 0.0
    for k in range(1, n + 1):  # a weight w at x has the moment x × (0, 0, -w) = (-x_y w, x_x w, 0)
        lev_f[k] = w_plate
        lev_m[k, 0] = -p[s, k, 1] * w_plate
        lev_m[k, 1] = p[s, k, 0] * w_plate
    lev_f[n] += mpay * g
    lev_m[n, 0] -= (R[s, n, 1, 2] * off + p[s, n, 1]) * mpay * g
    lev_m[n, 1] += (R[s, n, 0, 2] * off + p[s, n, 0]) * mpay * g
    for j in range(n):
        mx, my = 0.0, 0.0
        for i in range(6):
            b0, b1, b2 = bottom[j, i, 0], bottom[j, i, 1], bottom[j, i, 2]
            bx = p[s, j, 0] + R[s, j, 0, 0] * b0 + R[s, j, 0, 1] * b1 + R[s, j, 0, 2] * b2
            by = p[s, j, 1] + R[s, j, 1, 0] * b0 + R[s, j, 1, 1] * b1 + R[s, j, 1, 2] * b2
            bz = p[s, j, 2] + R[s, j, 2, 0] * b0 + R[s, j, 2, 1] * b1 + R[s, j, 2, 2] * b2
            c0, c1, c2 = top[j, i, 0], top[j, i, 1], top[j, i, 2]
            tx = p[s, j + 1, 0] + R[s, j + 1, 0, 0] * c0 + R[s, j + 1, 0, 1] * c1 + R[s, j + 1, 0, 2] * c2
            ty = p[s, j + 1, 1] + R[s, j + 1, 1, 0] * c0 + R[s, j + 1, 1, 1] * c1 + R[s, j + 1, 1, 2] * c2
            tz = p[s, j + 1, 2] + R[s, j + 1, 2, 0] * c0 + R[s, j + 1, 2, 1] * c1 + R[s, j + 1, 2, 2] * c2
            dx, dy, dz = tx - bx, ty - by, tz - bz
            L = math.sqrt(dx * dx + dy * dy + dz * dz)
            ux, uy, uz = dx / L, dy / L, dz / L
            g_u = -g * uz
            sf = ms + lever / L  # f⊥ = -s (g - (g·u) u), g = (0, 0, -g)
            t[j, i, 0], t[j, i, 1], t[j, i, 2] = tx, ty, tz
            u[j, i, 0], u[j, i, 1], u[j, i, 2] = ux, uy, uz
            fp[j, i, 0], fp[j, i, 1], fp[j, i, 2] = sf * g_u * ux, sf * g_u * uy, -sf * (-g - g_u * uz)
            gu[j, i] = g_u
            mx -= mm * (by + mc * uy) + ms * (ty - sc * uy)
            my += mm * (bx + mc * ux) + ms * (tx - sc * ux)
        lev_f[j] += 6.0 * w_leg
        lev_m[j, 0] += mx * g
        lev_m[j, 1] += my * g


def _invert_py(A, rhs):
    """Gauss–Jordan with partial pivoting on the 6×6 A in place, each row swap applied to
    rhs (6,) too: A becomes X with X·rhs = A₀⁻¹·rhs₀ and A₀⁻¹ = X up to a permutation of
    its columns (the same column sums). Returns False for an exactly singular (or
    non-finite) A₀."""
    for c in range(6):
        piv = c
        for r in range(c + 1, 6):
            if abs(A[r, c]) > abs(A[piv, c]):
                piv = r
        if A[piv, c] == 0.0 or not math.isfinite(A[piv, c]):
            return False
        if piv != c:
            for q in range(6):
                A[c, q], A[piv, q] = A[piv, q], A[c, q]
            rhs[c], rhs[piv] = rhs[piv], rhs[c]
        inv_p = 1.0 / A[c, c]
        A[c, c] = 1.0
        for q in range(6):
            A[c, q] *= inv_p
        for r in range(6):
            f = A[r, c]
            if r != c and f != 0.0:
                A[r, c] = 0.0
                for q in range(6):
                    A[r, q] -= f * A[c, q]
    return True


def _platform_rhs(R, p, s, j, t, fp, up, rhs):
    """The wrench platform j's legs must supply to plate j+1, in its axes, moments about its
    origin: the weight above (``up``: [N, downward] and its moment's x, y about the world
    origin) less the legs' transverse ball forces."""
    f0, f1, f2, m0, m1, m2 = 0.0, 0.0, -up[0], up[1], up[2], 0.0
    for i in range(6):
        tx, ty, tz = t[j, i, 0], t[j, i, 1], t[j, i, 2]
        fx, fy, fz = fp[j, i, 0], fp[j, i, 1], fp[j, i, 2]
        f0 -= fx
        f1 -= fy
        f2 -= fz
        m0 -= ty * fz - tz * fy
        m1 -= tz * fx - tx * fz
        m2 -= tx * fy - ty * fx
    px, py, pz = p[s, j + 1, 0], p[s, j + 1, 1], p[s, j + 1, 2]  # about the plate's origin: m - p × f
    m0 -= py * f2 - pz * f1
    m1 -= pz * f0 - px * f2
    m2 -= px * f1 - py * f0
    for a in range(3):  # in the plate's axes: Rᵀ
        r0, r1, r2 = R[s, j + 1, 0, a], R[s, j + 1, 1, a], R[s, j + 1, 2, a]
        rhs[a] = r0 * f0 + r1 * f1 + r2 * f2
        rhs[3 + a] = r0 * m0 + r1 * m1 + r2 * m2


def _platform_py(R, p, top, s, j, t, u, fp, gu, up, ms, A, rhs, forces, condition):
    """Platform j of stack s: the 6×6 system W a = rhs in the top plate's frame (moments
    about its origin; W's columns the legs' lines), its 1-norm condition number and the
    actuator forces (see :func:`_platform_rhs`)."""
    _rhs(R, p, s, j, t, fp, up, rhs)
    norm = 0.0
    for i in range(6):  # column i of W: [u_i, top_i × u_i] in the plate's axes
        ux, uy, uz = u[j, i, 0], u[j, i, 1], u[j, i, 2]
        a0 = R[s, j + 1, 0, 0] * ux + R[s, j + 1, 1, 0] * uy + R[s, j + 1, 2, 0] * uz
        a1 = R[s, j + 1, 0, 1] * ux + R[s, j + 1, 1, 1] * uy + R[s, j + 1, 2, 1] * uz
        a2 = R[s, j + 1, 0, 2] * ux + R[s, j + 1, 1, 2] * uy + R[s, j + 1, 2, 2] * uz
        c0, c1, c2 = top[j, i, 0], top[j, i, 1], top[j, i, 2]
        a3, a4, a5 = c1 * a2 - c2 * a1, c2 * a0 - c0 * a2, c0 * a1 - c1 * a0
        A[0, i], A[1, i], A[2, i], A[3, i], A[4, i], A[5, i] = a0, a1, a2, a3, a4, a5
        norm = max(norm, abs(a0) + abs(a1) + abs(a2) + abs(a3) + abs(a4) + abs(a5))
    if not _invert(A, rhs):
        condition[s, j] = math.nan
        for i in range(6):
            forces[s, j, i] = math.nan
        return
    inorm = 0.0
    for c in range(6):
        inorm = max(inorm, abs(A[0, c]) + abs(A[1, c]) + abs(A[2, c]) + abs(A[3, c]) + abs(A[4, c]) + abs(A[5, c]))
    condition[s, j] = norm * inorm
    for i in range(6):  # the actuator force adds the shaft's weight along the leg
        a_i = A[i, 0] * rhs[0] + A[i, 1] * rhs[1] + A[i, 2] * rhs[2]
        a_i += A[i, 3] * rhs[3] + A[i, 4] * rhs[4] + A[i, 5] * rhs[5]
        forces[s, j, i] = a_i + ms * gu[j, i]


def _stack_py(R, p, bottom, top, consts, s, t, u, fp, gu, lev_f, lev_m, A, rhs, up, forces, condition):
    """Stack ``s``: every platform, top down (the weight above plate j+1: levels j+1..n)."""
    n = R.shape[1] - 1
    _legs(R, p, bottom, top, consts, s, t, u, fp, gu, lev_f, lev_m)
    up[0], up[1], up[2] = 0.0, 0.0, 0.0
    for j in range(n - 1, -1, -1):
        up[0] += lev_f[j + 1]
        up[1] += lev_m[j + 1, 0]
        up[2] += lev_m[j + 1, 1]
        _platform(R, p, top, s, j, t, u, fp, gu, up, consts[2], A, rhs, forces, condition)


def _extras_py(R, p, s, consts, u, fp, gu, forces, lev_f, lev_m, ball, base):
    """After :func:`_stack_py` on stack ``s``: the ball forces (n, 6, 3) the top plates exert
    on the shaft tips (axial part plus the transverse f⊥) [N, world], and the base wrench
    [f, m] (6,) the mount applies to plate 0, moment about plate 0's origin, world axes
    [N, N·m] (plate 0's weight at its origin)."""
    n = R.shape[1] - 1
    ms, w0 = consts[2], consts[5] * consts[0]
    for j in range(n):
        for i in range(6):
            axial = forces[s, j, i] - ms * gu[j, i]
            for a in range(3):
                ball[s, j, i, a] = axial * u[j, i, a] + fp[j, i, a]
    weight, mx, my = w0, -p[s, 0, 1] * w0, p[s, 0, 0] * w0  # gravity's moment about the world origin
    for k in range(n + 1):
        weight += lev_f[k]
        mx += lev_m[k, 0]
        my += lev_m[k, 1]
    mx += p[s, 0, 1] * weight  # about plate 0's origin: m - p0 × (0, 0, -W)
    my -= p[s, 0, 0] * weight
    base[s, 0], base[s, 1], base[s, 2] = 0.0, 0.0, weight  # the mount balances gravity
    base[s, 3], base[s, 4], base[s, 5] = -mx, -my, 0.0


# The callees of the interpreted path; the compiled path binds the same names to compiled copies.
_legs, _invert, _rhs, _platform, _stack, _extras = (
    _legs_py,
    _invert_py,
    _platform_rhs,
    _platform_py,
    _stack_py,
    _extras_py,
)


class Grid:
    """A row-major n-dimensional array of Python floats indexed ``g[i, j, ...]``, enough for
    the loops above without numpy (``shape``, item reads and writes).

    Each innermost row is a list, found by the tuple of the leading indices."""

    __slots__ = ("_rows", "shape")

    def __init__(self, shape: Sequence[int], data: Sequence[float] | None = None) -> None:
        self.shape = tuple(int(d) for d in shape)
        size, last = math.prod(self.shape), self.shape[-1]
        values = [0.0] * size if data is None else [float(x) for x in data]
        if len(values) != size:
            raise ValueError(f"{len(values)} values do not fill the shape {self.shape}")
        prefixes: list[tuple[int, ...]] = [()]
        for d in self.shape[:-1]:
            prefixes = [(*pre, k) for pre in prefixes for k in range(d)]
        self._rows = {pre: values[r * last : (r + 1) * last] for r, pre in enumerate(prefixes)}

    def __getitem__(self, index: int | tuple[int, ...]) -> float:
        if isinstance(index, tuple):
            return self._rows[index[:-1]][index[-1]]
        return self._rows[()][index]

    def __setitem__(self, index: int | tuple[int, ...], value: float) -> None:
        if isinstance(index, tuple):
            self._rows[index[:-1]][index[-1]] = value
        else:
            self._rows[()][index] = value

    @property
    def data(self) -> list[float]:
        """The values in row-major order."""
        return [x for row in self._rows.values() for x in row]

    def nested(self) -> list:
        """The values as nested lists of the grid's shape."""
        if len(self.shape) == 1:
            return list(self._rows[()])
        out: list = [list(row) for row in self._rows.values()]
        for d in reversed(self.shape[1:-1]):
            out = [out[k : k + d] for k in range(0, len(out), d)]
        return out


def closed_form_pure(
    R: Grid, p: Grid, bottom: Grid, top: Grid, consts: Sequence[float]
) -> tuple[Grid, Grid, Grid, Grid]:
    """The statics of one stack (B = 1), interpreted, without numpy.

    Args:
        R: (1, n+1, 3, 3) plate rotations; p: (1, n+1, 3) plate positions, world [m].
        bottom, top: (n, 6, 3) joint centres in the bottom / top plate's frame [m].
        consts: the constants of :data:`CONSTANT_NAMES`.

    Returns:
        (forces (1, n, 6) [N, tension positive], condition (1, n), ball forces (1, n, 6, 3)
        [N, world], base wrench (1, 6) [N, N·m]; see :func:`_extras_py`).
    """
    n = R.shape[1] - 1
    forces, condition = Grid((1, n, 6)), Grid((1, n))
    ball, base = Grid((1, n, 6, 3)), Grid((1, 6))
    lev_f, lev_m = Grid((n + 1,)), Grid((n + 1, 2))
    t, u, fp, gu = Grid((n, 6, 3)), Grid((n, 6, 3)), Grid((n, 6, 3)), Grid((n, 6))
    A, rhs, up = Grid((6, 6)), Grid((6,)), Grid((3,))
    _stack(R, p, bottom, top, consts, 0, t, u, fp, gu, lev_f, lev_m, A, rhs, up, forces, condition)
    _extras(R, p, 0, consts, u, fp, gu, forces, lev_f, lev_m, ball, base)
    return forces, condition, ball, base
