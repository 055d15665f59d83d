"""A compiled kernel of the closed-form statics, for batches of stacks and single stacks.

The equilibrium is the one of :func:`~assembler_pin.closed_form.equilibrium` (each leg
balances its own weight; the top plate of each platform the weight above it and the six
ball forces; module docstring of :mod:`assembler_pin.closed_form`), written as plain loops
over the stacks, platforms and legs in :mod:`~assembler_pin.statics_loops` and compiled
here by numba (``cache=True``: compiled once per install and Python version, then loaded
from numba's cache). Per platform it solves the 6×6 system in the top plate's own frame
(moments about its origin) by Gauss–Jordan elimination with partial pivoting; the same
inverse gives the 1-norm condition number of :func:`~assembler_pin.statics.solve_statics`.
:func:`kernel_result` gives the whole :class:`~assembler_pin.statics.StaticsResult` of one
stack (ball forces and base wrench too).

The numpy path (:func:`~assembler_pin.closed_form.equilibrium`) stays the reference and the
fallback: it is used when numba is not installed, when ``ASSEMBLER_PIN_STATICS=numpy`` is
set in the environment, or with ``backend="numpy"``. The tests hold both, and
:func:`kernel_result`, to Pinocchio's statics (:func:`~assembler_pin.statics.solve_statics`)
to 1e-10 N.

Frames: world poses of plates 0..n; forces [N], tension positive.
"""

from __future__ import annotations

import importlib.util
import logging
import math
import os
import types
from typing import TYPE_CHECKING, Any

import numpy as np

from . import statics_loops as loops
from .closed_form import equilibrium, is_singular, line_conditions
from .exceptions import OptionsError
from .linalg import cross
from .model import AssemblerModel

if TYPE_CHECKING:
    from .kinematics import PlateArrays
    from .statics import StaticsResult

__all__ = [
    "BACKENDS",
    "ENV_VAR",
    "KERNEL_MIN_STACKS",
    "closed_form_forces",
    "kernel_available",
    "kernel_loaded",
    "kernel_result",
    "kernel_statics",
    "resolve_backend",
]

logger = logging.getLogger(__name__)

#: The backends of :func:`closed_form_forces`.
BACKENDS = ("auto", "numba", "numpy")

#: Environment variable forcing a backend (``numpy`` or ``numba``; unset: ``auto``).
ENV_VAR = "ASSEMBLER_PIN_STATICS"

#: ``auto`` loads the kernel for a call of at least this many stacks (importing numba and
#: loading the cached kernel take ~0.5–1 s; the numpy path does ~60k stacks/s).
KERNEL_MIN_STACKS = 5000

_kernel: Any = None  # the compiled function, once built (None: not yet; False: unavailable)
_exact_poses: Any = None  # the compiled pose check, built with the kernel
_stack, _extras = loops._stack_py, loops._extras_py  # interpreted here; the kernels call compiled copies
_NO_BALL, _NO_BASE = np.empty((1, 1, 1, 1)), np.empty((1, 1))  # placeholders of a forces-only call


def _kernel_py(R, p, bottom, top, consts, forces, condition, ball, base, full):  # pragma: no cover - compiled
    """consts: :data:`~assembler_pin.statics_loops.CONSTANT_NAMES`. Fills forces (B, n, 6)
    and condition (B, n), stack by stack (:func:`~assembler_pin.statics_loops._stack_py`), and
    with ``full`` the ball forces (B, n, 6, 3) and base wrenches (B, 6) too
    (:func:`~assembler_pin.statics_loops._extras_py`; without, ``ball`` and ``base`` are not read)."""
    B, n = R.shape[0], R.shape[1] - 1
    lev_f, lev_m = np.zeros(n + 1), np.zeros((n + 1, 2))
    t, u, fp, gu = np.zeros((n, 6, 3)), np.zeros((n, 6, 3)), np.zeros((n, 6, 3)), np.zeros((n, 6))
    A, rhs, up = np.zeros((6, 12)), np.zeros(6), np.zeros(3)
    for s in range(B):
        _stack(R, p, bottom, top, consts, s, t, u, fp, gu, lev_f, lev_m, A, rhs, up, forces, condition)
        if full:
            _extras(R, p, s, consts, u, fp, gu, forces, lev_f, lev_m, ball, base)


#: A pose the compiled check passes as is: bottom row [0, 0, 0, 1] to 1e-12 and |RᵀR − I| at
#: most this (below it :func:`~assembler_pin.kinematics.checked_rotations` keeps R as given).
EXACT_ROTATION_TOL = 1e-14


def _exact_poses_py(M, tol):  # pragma: no cover - compiled
    """Whether every (4, 4) matrix of M (m, 4, 4) is finite, has the bottom row [0, 0, 0, 1]
    to 1e-12 and an orthonormal 3×3 block to ``tol`` (:data:`EXACT_ROTATION_TOL`) with det > 0."""
    for k in range(M.shape[0]):
        for i in range(4):
            for j in range(4):
                if not math.isfinite(M[k, i, j]):
                    return False
        bottom = max(abs(M[k, 3, 0]), abs(M[k, 3, 1]), abs(M[k, 3, 2]), abs(M[k, 3, 3] - 1.0))
        if not bottom <= 1e-12:
            return False
        for a in range(3):
            for b in range(3):
                g = M[k, 0, a] * M[k, 0, b] + M[k, 1, a] * M[k, 1, b] + M[k, 2, a] * M[k, 2, b]
                if abs(g - (1.0 if a == b else 0.0)) > tol:
                    return False
        det = (
            M[k, 0, 0] * (M[k, 1, 1] * M[k, 2, 2] - M[k, 1, 2] * M[k, 2, 1])
            - M[k, 0, 1] * (M[k, 1, 0] * M[k, 2, 2] - M[k, 1, 2] * M[k, 2, 0])
            + M[k, 0, 2] * (M[k, 1, 0] * M[k, 2, 1] - M[k, 1, 1] * M[k, 2, 0])
        )
        if not det > 0.0:
            return False
    return True


def _build_kernel() -> Any:
    """Compile (or load from numba's cache) the kernel; False when numba is missing.

    The loops of :mod:`~assembler_pin.statics_loops` are compiled as copies whose globals
    name the compiled callees, so the interpreted originals keep calling each other."""
    try:
        import numba
    except ImportError:
        return False
    jit = numba.njit(cache=True, nogil=True)
    scope: dict[str, Any] = {"math": math, "np": np, "__name__": __name__}
    parts = (
        ("_legs", loops._legs_py),
        ("_invert", loops._invert_py),
        ("_rhs", loops._platform_rhs),
        ("_platform", loops._platform_py),
        ("_stack", loops._stack_py),
        ("_extras", loops._extras_py),
        ("_kernel", _kernel_py),
        ("_exact_poses", _exact_poses_py),
    )
    for name, func in parts:  # callees first: the callers see them compiled
        scope[name] = jit(types.FunctionType(func.__code__, scope, func.__name__))
    global _exact_poses
    _exact_poses = scope["_exact_poses"]
    return scope["_kernel"]


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
    return np.array(loops.constants(am.config))


def _numpy_forces(am: AssemblerModel, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The reference path: :func:`~assembler_pin.closed_form.equilibrium` and the condition
    number of the legs' lines in each top plate's frame (:func:`~assembler_pin.closed_form.line_conditions`)."""

    eq, _ = equilibrium(am, R, p)
    u_local = np.einsum("bjka,bjik->bjia", R[:, 1:], eq.u)
    lines_t = np.concatenate([u_local, cross(am.geometry.top_in_plate, u_local)], axis=-1)  # (B, n, legs, 6)
    return eq.forces, line_conditions(lines_t)[1]


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
    bottom, top = np.ascontiguousarray(geo.bottom_in_plate), np.ascontiguousarray(geo.top_in_plate)
    _kernel(R, p, bottom, top, _constants(am), forces, condition, _NO_BALL, _NO_BASE, False)
    return forces, condition


def kernel_loaded() -> bool:
    """Whether the compiled kernel is loaded in this process already (no compile, no import)."""
    return _kernel not in (None, False)


def kernel_statics(am: AssemblerModel, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, ...]:
    """The whole closed-form statics of B stacks on the compiled kernel.

    Args:
        R: (B, n+1, 3, 3) plate rotations; p: (B, n+1, 3) plate positions, world [m]
            (checked by the caller).

    Returns:
        (forces (B, n, 6) [N, tension positive], ball forces (B, n, 6, 3) the top plates
        exert on the shaft tips [N, world], base wrenches (B, 6) ``[f, m]`` the mount applies
        to plate 0, moment about its origin, world axes [N, N·m], condition (B, n)); NaN
        forces where a platform's system is exactly singular.

    Raises:
        OptionsError: numba is not installed.
    """
    if not kernel_available():
        raise OptionsError("the numba statics backend needs numba: pip install numba")
    R = np.ascontiguousarray(R, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    B, n = R.shape[0], am.n
    forces, condition = np.empty((B, n, 6)), np.empty((B, n))
    ball, base = np.empty((B, n, 6, 3)), np.empty((B, 6))
    geo = am.geometry
    bottom, top = np.ascontiguousarray(geo.bottom_in_plate), np.ascontiguousarray(geo.top_in_plate)
    _kernel(R, p, bottom, top, _constants(am), forces, condition, ball, base, True)
    return forces, ball, base, condition


def kernel_result(
    am: AssemblerModel, plates: PlateArrays | np.ndarray, raise_on_singular: bool = False
) -> StaticsResult:
    """:func:`~assembler_pin.statics.solve_statics` on the compiled kernel: the same
    :class:`~assembler_pin.statics.StaticsResult` (forces, ball forces, base wrench, condition
    numbers, the singular flag and error of :data:`~assembler_pin.statics.CONDITION_LIMIT`),
    which the tests hold to Pinocchio's.

    Args:
        plates: checked plate arrays (:func:`~assembler_pin.kinematics.plate_arrays`), or
            the n+1 plate poses as a float array (n+1, 4, 4), plate 0 first. Matrices that
            are exact rotations (:data:`EXACT_ROTATION_TOL`) pass a compiled check; any
            other array goes through :func:`~assembler_pin.kinematics.plate_arrays`, which
            projects a rotation off by less than its tolerance and refuses the rest with its
            message.

    Raises:
        PoseError: the matrices are not n+1 plate poses.
        SingularConfigurationError: with ``raise_on_singular``, a platform's condition number
            exceeds the limit.
    """
    from .kinematics import plate_arrays
    from .statics import StaticsResult

    if not kernel_available():
        raise OptionsError("the numba statics backend needs numba: pip install numba")
    if (
        isinstance(plates, np.ndarray)
        and plates.dtype == np.float64
        and plates.shape == (am.n + 1, 4, 4)
        and _exact_poses(plates, EXACT_ROTATION_TOL)
    ):
        R, p = plates[None, :, :3, :3], plates[None, :, :3, 3]
    else:  # plate arrays (checked once) or anything else: the package's validation
        checked = plate_arrays(am, plates)
        R, p = checked.R[None], checked.p[None]
    forces, ball, base, condition = kernel_statics(am, R, p)
    condition = condition[0]
    singular = is_singular(condition, raise_on_singular)
    return StaticsResult(forces[0], ball[0], base[0], condition, singular)
