"""The closed-form statics as plain loops: the one source of the compiled kernel and of the
pure-Python path.

The equilibrium is the one of :func:`~assembler_pin.closed_form.equilibrium` (each leg
balances its own weight; the top plate of each platform the weight above it and the six
ball forces; module docstring of :mod:`assembler_pin.closed_form`). The loops below use only
scalar arithmetic, :mod:`math` and ``x[i, j, ...]`` indexing, so the same code runs

* compiled by numba on numpy arrays (:mod:`~assembler_pin.statics_kernel` compiles copies
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
    from .config import AssemblerConfig

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
    lever = mc * mm - sc * ms
    n = R.shape[1] - 1
    for k in range(n + 1):
        lev_f[k] = 0.0
        lev_m[k, 0] = 0.0
        lev_m[k, 1] = 0.0
    for k in range(1, n + 1):  # a weight w at x has the moment x × (0, 0, -w) = (-x_y w, x_x w, 0)
        lev_f[k] += mplate * g
        lev_m[k, 0] -= p[s, k, 1] * mplate * g
        lev_m[k, 1] += p[s, k, 0] * mplate * g
    lev_f[n] += mpay * g
    lev_m[n, 0] -= (R[s, n, 1, 2] * off + p[s, n, 1]) * mpay * g
    lev_m[n, 1] += (R[s, n, 0, 2] * off + p[s, n, 0]) * mpay * g
    for j in range(n):
        for i in range(6):
            bx, by, bz = p[s, j, 0], p[s, j, 1], p[s, j, 2]
            for c in range(3):
                bx += R[s, j, 0, c] * bottom[j, i, c]
                by += R[s, j, 1, c] * bottom[j, i, c]
                bz += R[s, j, 2, c] * bottom[j, i, c]
            for a in range(3):
                t[j, i, a] = p[s, j + 1, a]
                for c in range(3):
                    t[j, i, a] += R[s, j + 1, a, c] * top[j, i, c]
            dx, dy, dz = t[j, i, 0] - bx, t[j, i, 1] - by, t[j, i, 2] - bz
            L = math.sqrt(dx * dx + dy * dy + dz * dz)
            u[j, i, 0], u[j, i, 1], u[j, i, 2] = dx / L, dy / L, dz / L
            gu[j, i] = -g * u[j, i, 2]
            sf = ms + lever / L
            for a in range(3):  # f⊥ = -s (g - (g·u) u), g = (0, 0, -g)
                fp[j, i, a] = -sf * ((-g if a == 2 else 0.0) - gu[j, i] * u[j, i, a])
            cx = mm * (bx + mc * u[j, i, 0]) + ms * (t[j, i, 0] - sc * u[j, i, 0])
            cy = mm * (by + mc * u[j, i, 1]) + ms * (t[j, i, 1] - sc * u[j, i, 1])
            lev_f[j] += (mm + ms) * g
            lev_m[j, 0] -= cy * g
            lev_m[j, 1] += cx * g


def _invert_py(A):
    """Gauss–Jordan with partial pivoting on A = [M | I] (6×12) in place: A[:, 6:] becomes
    M⁻¹. Returns False for an exactly singular (or non-finite) M."""
    for c in range(6):
        piv = c
        for r in range(c + 1, 6):
            if abs(A[r, c]) > abs(A[piv, c]):
                piv = r
        if A[piv, c] == 0.0 or not math.isfinite(A[piv, c]):
            return False
        if piv != c:
            for q in range(12):
                A[c, q], A[piv, q] = A[piv, q], A[c, q]
        inv_p = 1.0 / A[c, c]
        for q in range(12):
            A[c, q] *= inv_p
        for r in range(6):
            if r != c and A[r, c] != 0.0:
                f = A[r, c]
                for q in range(12):
                    A[r, q] -= f * A[c, q]
    return True


def _platform_rhs(R, p, s, j, t, fp, up, rhs):
    """The wrench platform j's legs must supply to plate j+1, in its axes, moments about its
    origin: the weight above (``up``: [N, downward] and its moment's x, y about the world
    origin) less the legs' transverse ball forces."""
    for a in range(6):
        rhs[a] = 0.0
    rhs[2], rhs[3], rhs[4] = -up[0], up[1], up[2]
    for i in range(6):
        tx, ty, tz = t[j, i, 0], t[j, i, 1], t[j, i, 2]
        fx, fy, fz = fp[j, i, 0], fp[j, i, 1], fp[j, i, 2]
        rhs[0] -= fx
        rhs[1] -= fy
        rhs[2] -= fz
        rhs[3] -= ty * fz - tz * fy
        rhs[4] -= tz * fx - tx * fz
        rhs[5] -= tx * fy - ty * fx
    px, py, pz = p[s, j + 1, 0], p[s, j + 1, 1], p[s, j + 1, 2]  # about the plate's origin: m - p × f
    m0 = rhs[3] - (py * rhs[2] - pz * rhs[1])
    m1 = rhs[4] - (pz * rhs[0] - px * rhs[2])
    m2 = rhs[5] - (px * rhs[1] - py * rhs[0])
    f0, f1, f2 = rhs[0], rhs[1], rhs[2]
    for a in range(3):  # in the plate's axes: Rᵀ
        rhs[a] = R[s, j + 1, 0, a] * f0 + R[s, j + 1, 1, a] * f1 + R[s, j + 1, 2, a] * f2
        rhs[3 + a] = R[s, j + 1, 0, a] * m0 + R[s, j + 1, 1, a] * m1 + R[s, j + 1, 2, a] * m2


def _platform_py(R, p, top, s, j, t, u, fp, gu, up, ms, A, rhs, forces, condition):
    """Platform j of stack s: the 6×6 system in the top plate's frame (moments about its
    origin), its 1-norm condition number and the actuator forces (see :func:`_platform_rhs`)."""
    _rhs(R, p, s, j, t, fp, up, rhs)
    norm = 0.0
    for i in range(6):  # A = [Wᵀ | I], Wᵀ's rows (one per leg) [u_l, top × u_l]
        for a in range(3):
            A[i, a] = R[s, j + 1, 0, a] * u[j, i, 0] + R[s, j + 1, 1, a] * u[j, i, 1] + R[s, j + 1, 2, a] * u[j, i, 2]
        A[i, 3] = top[j, i, 1] * A[i, 2] - top[j, i, 2] * A[i, 1]
        A[i, 4] = top[j, i, 2] * A[i, 0] - top[j, i, 0] * A[i, 2]
        A[i, 5] = top[j, i, 0] * A[i, 1] - top[j, i, 1] * A[i, 0]
        for c in range(6):
            A[i, 6 + c] = 1.0 if c == i else 0.0
        norm = max(norm, abs(A[i, 0]) + abs(A[i, 1]) + abs(A[i, 2]) + abs(A[i, 3]) + abs(A[i, 4]) + abs(A[i, 5]))
    if not _invert(A):
        condition[s, j] = math.nan
        for i in range(6):
            forces[s, j, i] = math.nan
        return
    inorm = 0.0
    for i in range(6):
        inorm = max(inorm, abs(A[i, 6]) + abs(A[i, 7]) + abs(A[i, 8]) + abs(A[i, 9]) + abs(A[i, 10]) + abs(A[i, 11]))
    condition[s, j] = norm * inorm
    for i in range(6):  # W a = rhs: a = (Wᵀ)⁻ᵀ rhs; the actuator force adds the shaft's weight along the leg
        a_i = 0.0
        for c in range(6):
            a_i += A[c, 6 + i] * rhs[c]
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
    A, rhs, up = Grid((6, 12)), Grid((6,)), Grid((3,))
    _stack(R, p, bottom, top, consts, 0, t, u, fp, gu, lev_f, lev_m, A, rhs, up, forces, condition)
    _extras(R, p, 0, consts, u, fp, gu, forces, lev_f, lev_m, ball, base)
    return forces, condition, ball, base
