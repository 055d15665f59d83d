"""A compiled kernel of the closed-form statics, for batches of stacks and single stacks.

The equilibrium is the one of :func:`~assembler_pin.gradients.equilibrium` (each leg
balances its own weight; the top plate of each platform the weight above it and the six
ball forces; module docstring of :mod:`assembler_pin.gradients`), written as plain loops
over the stacks, platforms and legs and compiled by numba (``cache=True``: compiled once
per install and Python version, then loaded from numba's cache). Per platform it solves
the 6×6 system in the top plate's own frame (moments about its origin) by Gauss–Jordan
elimination with partial pivoting; the same inverse gives the 1-norm condition number of
:func:`~assembler_pin.statics.solve_statics`.

The numpy path (:func:`~assembler_pin.gradients.equilibrium`) stays the reference and the
fallback: it is used when numba is not installed, when ``ASSEMBLER_PIN_STATICS=numpy`` is
set in the environment, or with ``backend="numpy"``. The tests hold both to Pinocchio's
statics (:func:`~assembler_pin.statics.solve_statics`) to 1e-10 N.

Frames: world poses of plates 0..n; forces [N], tension positive.
"""

from __future__ import annotations

import importlib.util
import logging
import os
from typing import Any

import numpy as np

from .exceptions import OptionsError
from .linalg import cross, inverse_or_nan
from .model import AssemblerModel

__all__ = ["BACKENDS", "ENV_VAR", "KERNEL_MIN_STACKS", "closed_form_forces", "kernel_available", "resolve_backend"]

logger = logging.getLogger(__name__)

#: The backends of :func:`closed_form_forces`.
BACKENDS = ("auto", "numba", "numpy")

#: Environment variable forcing a backend (``numpy`` or ``numba``; unset: ``auto``).
ENV_VAR = "ASSEMBLER_PIN_STATICS"

#: ``auto`` loads the kernel for a call of at least this many stacks (importing numba and
#: loading the cached kernel take ~0.5–1 s; the numpy path does ~60k stacks/s).
KERNEL_MIN_STACKS = 5000

_kernel: Any = None  # the compiled function, once built (None: not yet; False: unavailable)
# the compiled parts, set by _build_kernel (the kernel calls them by these names)
_legs: Any = None
_invert: Any = None
_platform: Any = None


def _legs_py(R, p, bottom, top, consts, s, t, u, fp, gu, lev_f, lev_m):  # pragma: no cover - compiled
    """Stack ``s``: top joints t, leg directions u, transverse ball forces fp, gravity along
    the legs gu (n, 6, ...), and each level's weight lev_f [N, downward] and its moment's
    x, y about the world origin lev_m (level k: plate k, the legs of SP k, the payload)."""
    g, mm, ms, mc = consts[0], consts[1], consts[2], consts[3]
    sc, mplate, mpay, off = consts[4], consts[5], consts[6], consts[7]
    lever = mc * mm - sc * ms
    n = R.shape[1] - 1
    lev_f[:] = 0.0
    lev_m[:] = 0.0
    for k in range(1, n + 1):  # a weight w at x has the moment x × (0, 0, -w) = (-x_y w, x_x w, 0)
        lev_f[k] += mplate * g
        lev_m[k, 0] -= p[s, k, 1] * mplate * g
        lev_m[k, 1] += p[s, k, 0] * mplate * g
    lev_f[n] += mpay * g
    lev_m[n, 0] -= (R[s, n, 1, 2] * off + p[s, n, 1]) * mpay * g
    lev_m[n, 1] += (R[s, n, 0, 2] * off + p[s, n, 0]) * mpay * g
    bx = np.zeros(3)
    for j in range(n):
        for i in range(6):
            for a in range(3):
                bx[a] = p[s, j, a]
                t[j, i, a] = p[s, j + 1, a]
                for c in range(3):
                    bx[a] += R[s, j, a, c] * bottom[j, i, c]
                    t[j, i, a] += R[s, j + 1, a, c] * top[j, i, c]
            dx, dy, dz = t[j, i, 0] - bx[0], t[j, i, 1] - bx[1], t[j, i, 2] - bx[2]
            L = np.sqrt(dx * dx + dy * dy + dz * dz)
            u[j, i, 0], u[j, i, 1], u[j, i, 2] = dx / L, dy / L, dz / L
            gu[j, i] = -g * u[j, i, 2]
            sf = ms + lever / L
            for a in range(3):  # f⊥ = -s (g - (g·u) u), g = (0, 0, -g)
                fp[j, i, a] = -sf * ((-g if a == 2 else 0.0) - gu[j, i] * u[j, i, a])
            cx = mm * (bx[0] + mc * u[j, i, 0]) + ms * (t[j, i, 0] - sc * u[j, i, 0])
            cy = mm * (bx[1] + mc * u[j, i, 1]) + ms * (t[j, i, 1] - sc * u[j, i, 1])
            lev_f[j] += (mm + ms) * g
            lev_m[j, 0] -= cy * g
            lev_m[j, 1] += cx * g


def _invert_py(A):  # pragma: no cover - compiled
    """Gauss–Jordan with partial pivoting on A = [M | I] (6×12) in place: A[:, 6:] becomes
    M⁻¹. Returns False for an exactly singular (or non-finite) M."""
    for c in range(6):
        piv = c
        for r in range(c + 1, 6):
            if abs(A[r, c]) > abs(A[piv, c]):
                piv = r
        if A[piv, c] == 0.0 or not np.isfinite(A[piv, c]):
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


def _platform_py(R, p, top, s, j, t, u, fp, gu, up, ms, A, rhs, forces, condition):  # pragma: no cover - compiled
    """Platform j of stack s: the 6×6 system in the top plate's frame (moments about its
    origin), its 1-norm condition number and the actuator forces. ``up``: the weight above
    plate j+1 [N, downward] and its moment's x, y about the world origin."""
    rhs[:] = 0.0  # world wrench about the world origin: the weight above less the legs' f⊥
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
    norm = 0.0
    for i in range(6):  # A = [Wᵀ | I], Wᵀ's rows (one per leg) [u_l, top × u_l]
        for a in range(3):
            A[i, a] = R[s, j + 1, 0, a] * u[j, i, 0] + R[s, j + 1, 1, a] * u[j, i, 1] + R[s, j + 1, 2, a] * u[j, i, 2]
        tp = top[j, i]
        A[i, 3] = tp[1] * A[i, 2] - tp[2] * A[i, 1]
        A[i, 4] = tp[2] * A[i, 0] - tp[0] * A[i, 2]
        A[i, 5] = tp[0] * A[i, 1] - tp[1] * A[i, 0]
        for c in range(6):
            A[i, 6 + c] = 1.0 if c == i else 0.0
        norm = max(norm, abs(A[i, 0]) + abs(A[i, 1]) + abs(A[i, 2]) + abs(A[i, 3]) + abs(A[i, 4]) + abs(A[i, 5]))
    if not _invert(A):
        condition[s, j] = np.nan
        forces[s, j, :] = np.nan
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


def _kernel_py(R, p, bottom, top, consts, forces, condition):  # pragma: no cover - compiled
    """consts: gravity, motor mass, shaft mass, motor CoM, shaft CoM, plate mass, payload
    mass, payload offset. Fills forces (B, n, 6) and condition (B, n)."""
    B, n = R.shape[0], R.shape[1] - 1
    lev_f, lev_m = np.zeros(n + 1), np.zeros((n + 1, 2))
    t, u, fp, gu = np.zeros((n, 6, 3)), np.zeros((n, 6, 3)), np.zeros((n, 6, 3)), np.zeros((n, 6))
    A, rhs, up = np.zeros((6, 12)), np.zeros(6), np.zeros(3)
    for s in range(B):
        _legs(R, p, bottom, top, consts, s, t, u, fp, gu, lev_f, lev_m)
        up[:] = 0.0
        for j in range(n - 1, -1, -1):  # the weight above plate j+1: levels j+1..n
            up[0] += lev_f[j + 1]
            up[1] += lev_m[j + 1, 0]
            up[2] += lev_m[j + 1, 1]
            _platform(R, p, top, s, j, t, u, fp, gu, up, consts[2], A, rhs, forces, condition)


def _build_kernel() -> Any:
    """Compile (or load from numba's cache) the kernel; False when numba is missing."""
    try:
        import numba
    except ImportError:
        return False
    jit = numba.njit(cache=True, nogil=True)
    module = globals()
    for name in ("_legs", "_invert", "_platform", "_kernel_nb"):  # callees first: the callers see them
        module[name] = jit(module[f"{name.removesuffix('_nb')}_py"])
    return module["_kernel_nb"]


def kernel_available() -> bool:
    """Whether the compiled kernel can be used (numba importable); compiles it on first call
    (or loads it from numba's cache)."""
    global _kernel
    if _kernel is None:
        _kernel = _build_kernel()
        if _kernel is False:
            logger.info("numba is not installed: the statics use the numpy path")
    return _kernel is not False


def resolve_backend(backend: str | None = None, stacks: int = 1) -> str:
    """``numba`` or ``numpy`` for a call on ``stacks`` stacks.

    ``backend`` (default: the :data:`ENV_VAR` setting, else ``auto``): ``numpy``, ``numba``
    (refused without numba), or ``auto``: numba when it is installed and either the kernel
    is loaded in this process already or the call has at least :data:`KERNEL_MIN_STACKS`
    stacks (a one-off small call does not pay numba's import and the kernel's load).

    Raises:
        OptionsError: an unknown backend, or ``numba`` without numba.
    """
    choice = backend if backend is not None else os.environ.get(ENV_VAR, "") or "auto"
    if choice not in BACKENDS:
        raise OptionsError(f"statics backend must be one of {', '.join(BACKENDS)}, got {choice!r}")
    if choice == "numpy":
        return "numpy"
    if choice == "auto":
        if _kernel is False or importlib.util.find_spec("numba") is None:
            return "numpy"
        if _kernel is None and stacks < KERNEL_MIN_STACKS:
            return "numpy"
    if kernel_available():
        return "numba"
    raise OptionsError("the numba statics backend needs numba: pip install numba")


def _constants(am: AssemblerModel) -> np.ndarray:
    cfg, leg = am.config, am.config.leg
    return np.array(
        [
            cfg.gravity,
            leg.motor_mass,
            leg.shaft_mass,
            leg.motor_com,
            leg.shaft_com,
            cfg.plate.mass,
            cfg.payload.mass,
            cfg.payload.offset,
        ],
    )


def _numpy_forces(am: AssemblerModel, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The reference path: :func:`~assembler_pin.gradients.equilibrium` and the condition
    number of the legs' lines in each top plate's frame."""
    from .gradients import equilibrium

    eq, _ = equilibrium(am, R, p)
    u_local = np.einsum("bjka,bjik->bjia", R[:, 1:], eq.u)
    lines_t = np.concatenate([u_local, cross(am.geometry.top_in_plate, u_local)], axis=-1)  # (B, n, legs, 6)
    inverse_t = inverse_or_nan(lines_t)
    condition = np.abs(lines_t).sum(axis=-1).max(axis=-1) * np.abs(inverse_t).sum(axis=-1).max(axis=-1)
    return eq.forces, condition


def closed_form_forces(
    am: AssemblerModel, R: np.ndarray, p: np.ndarray, backend: str | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Actuator forces and condition numbers of B stacks by the closed-form statics.

    Args:
        R: (B, n+1, 3, 3) plate rotations; p: (B, n+1, 3) plate positions, world [m]
            (checked by the caller).
        backend: ``auto``, ``numba`` or ``numpy`` (see :func:`resolve_backend`).

    Returns:
        (forces (B, n, 6) [N, tension positive], condition (B, n): 1-norm condition number
        of each platform's 6×6 system; NaN for both where the system is exactly singular).
    """
    if resolve_backend(backend, R.shape[0]) == "numpy":
        return _numpy_forces(am, R, p)
    R = np.ascontiguousarray(R, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    B, n = R.shape[0], am.n
    forces = np.empty((B, n, 6))
    condition = np.empty((B, n))
    geo = am.geometry
    _kernel(
        R,
        p,
        np.ascontiguousarray(geo.bottom_in_plate),
        np.ascontiguousarray(geo.top_in_plate),
        _constants(am),
        forces,
        condition,
    )
    return forces, condition
