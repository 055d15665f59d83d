"""A compiled kernel of the closed-form statics, for batches of stacks and single stacks.

The equilibrium is the one of :func:`~assembler_pin.statics.closed_form.equilibrium` (each leg
balances its own weight; the top plate of each platform the weight above it and the six
ball forces; module docstring of :mod:`assembler_pin.statics.closed_form`), written as plain loops
over the stacks, platforms and legs in :mod:`~assembler_pin.statics.loops` and compiled
here by numba (``cache=True``: compiled once per install and Python version, then loaded
from numba's cache). Per platform it solves the 6×6 system in the top plate's own frame
(moments about its origin) by Gauss–Jordan elimination with partial pivoting; the same
inverse gives the 1-norm condition number of :func:`~assembler_pin.statics.engine.solve_statics`.
The loops' callees are inlined into the compiled kernel. numba checks a cached kernel against
the timestamp of this file only: in a working copy, a change to
:mod:`~assembler_pin.statics.loops` alone is seen once this file is touched too (or its
``__pycache__/statics_kernel.*.nbi`` files are deleted); an install replaces both.

:func:`kernel_result` gives the whole :class:`~assembler_pin.statics.result.StaticsResult` of one
stack (ball forces and base wrench too) from one compiled call that checks the poses first
(:func:`_rotations_ok_py`, :func:`_exact_poses_py`) and returns the largest condition
number; poses it does not pass go through :func:`~assembler_pin.kinematics.plate_arrays`,
which refuses them with its message or checks (and projects) them. The model's arrays the
kernel reads are built once per model.

This kernel is the package's one statics engine (numba is a dependency): the numpy
closed form (:func:`reference_forces`, from :func:`~assembler_pin.statics.closed_form.equilibrium`)
and Pinocchio's statics (:func:`~assembler_pin.statics.pinocchio_statics.pinocchio_statics`)
stay as the tests' independent references, which hold the kernel and :func:`kernel_result`
to both to 1e-10 N.

Frames: world poses of plates 0..n; forces [N], tension positive.
"""

from __future__ import annotations

import logging
import math
import types
import weakref
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..common.linalg import cross
from ..kinematics.poses import ORTHONORMAL_TOL, PlateArrays, plate_arrays
from ..model.assembler import AssemblerModel
from . import loops
from .closed_form import CONDITION_LIMIT, equilibrium, line_conditions, raise_singular
from .result import StaticsResult

__all__ = [
    "closed_form_forces",
    "kernel_available",
    "kernel_loaded",
    "kernel_result",
    "kernel_statics",
    "reference_forces",
]

logger = logging.getLogger(__name__)

_kernel: Any = None  # the compiled function, once built (None: not yet)
_arrays_stack: Any = None  # the compiled single-stack calls, built with the kernel
_matrix_stack: Any = None
_stack, _extras = loops._stack_py, loops._extras_py  # interpreted here; the kernels call compiled copies
_NO_BALL, _NO_BASE = np.empty((1, 1, 1, 1)), np.empty((1, 1))  # placeholders of a forces-only call

#: What the single-stack calls return when their compiled check does not pass the poses
#: (a condition number is at least 1): the package's validation then decides.
NOT_PASSED = -1.0

#: The compiled check of plate arrays passes rotations orthonormal and of det +1 to this,
#: half of :data:`~assembler_pin.kinematics.ORTHONORMAL_TOL`: whatever it passes, the
#: package's check (the same test, other rounding) passes too; the rest goes to that check.
ARRAYS_ROTATION_TOL = 0.5 * ORTHONORMAL_TOL


def _kernel_py(R, p, bottom, top, consts, forces, condition, ball, base, full):  # pragma: no cover - compiled
    """consts: :data:`~assembler_pin.statics.loops.CONSTANT_NAMES`. Fills forces (B, n, 6)
    and condition (B, n), stack by stack (:func:`~assembler_pin.statics.loops._stack_py`), and
    with ``full`` the ball forces (B, n, 6, 3) and base wrenches (B, 6) too
    (:func:`~assembler_pin.statics.loops._extras_py`; without, ``ball`` and ``base`` are not read)."""
    B, n = R.shape[0], R.shape[1] - 1
    lev_f, lev_m = np.zeros(n + 1), np.zeros((n + 1, 2))
    t, u, fp, gu = np.zeros((n, 6, 3)), np.zeros((n, 6, 3)), np.zeros((n, 6, 3)), np.zeros((n, 6))
    A, rhs, up = np.zeros((6, 6)), np.zeros(6), np.zeros(3)
    for s in range(B):
        _stack(R, p, bottom, top, consts, s, t, u, fp, gu, lev_f, lev_m, A, rhs, up, forces, condition)
        if full:
            _extras(R, p, s, consts, u, fp, gu, forces, lev_f, lev_m, ball, base)


def _one_stack_py(R, p, bottom, top, consts, forces, condition, ball, base):  # pragma: no cover - compiled
    """The full kernel on one stack: R (1, n+1, 3, 3), p (1, n+1, 3) [m, world]; fills forces
    (n, 6) [N], condition (n,), ball forces (n, 6, 3) [N, world], base (6,) [N, N·m] and
    returns the largest condition number (NaN when a platform is exactly singular)."""
    n = R.shape[1] - 1
    shaped = (forces.reshape((1, n, 6)), condition.reshape((1, n)), ball.reshape((1, n, 6, 3)), base.reshape((1, 6)))
    _kernel(R, p, bottom, top, consts, shaped[0], shaped[1], shaped[2], shaped[3], True)
    worst = 0.0
    for j in range(n):
        if math.isnan(condition[j]):
            return math.nan
        worst = max(worst, condition[j])
    return worst


def _arrays_stack_py(R, p, tol, bottom, top, consts, forces, condition, ball, base):  # pragma: no cover - compiled
    """:func:`_one_stack_py` on plate arrays R (n+1, 3, 3), p (n+1, 3) [m, world], first
    checked by :func:`_rotations_ok_py` to ``tol`` unless ``tol`` is 0 (arrays checked
    already); :data:`NOT_PASSED` when the check fails."""
    if tol > 0.0 and not _rotations_ok(R, p, tol):
        return NOT_PASSED
    m = R.shape[0]
    return _one_stack(R.reshape((1, m, 3, 3)), p.reshape((1, m, 3)), bottom, top, consts, forces, condition, ball, base)


def _matrix_stack_py(M, tol, bottom, top, consts, forces, condition, ball, base):  # pragma: no cover - compiled
    """:func:`_one_stack_py` on plate poses M (n+1, 4, 4) [m, world] that pass
    :func:`_exact_poses_py` to ``tol``; :data:`NOT_PASSED` when they do not."""
    if not _exact_poses(M, tol):
        return NOT_PASSED
    m = M.shape[0]
    R, p = np.empty((1, m, 3, 3)), np.empty((1, m, 3))
    for k in range(m):
        for a in range(3):
            p[0, k, a] = M[k, a, 3]
            for b in range(3):
                R[0, k, a, b] = M[k, a, b]
    return _one_stack(R, p, bottom, top, consts, forces, condition, ball, base)


def _rotations_ok_py(R, p, tol):  # pragma: no cover - compiled
    """Whether R (m, 3, 3) and p (m, 3) are finite and every R[k] is orthonormal
    (|RᵀR − I| ≤ ``tol``) with |det − 1| ≤ ``tol``."""
    for k in range(R.shape[0]):
        for a in range(3):
            if not math.isfinite(p[k, a]):
                return False
            for b in range(3):
                if not math.isfinite(R[k, a, b]):
                    return False
        for a in range(3):
            for b in range(3):
                g = R[k, 0, a] * R[k, 0, b] + R[k, 1, a] * R[k, 1, b] + R[k, 2, a] * R[k, 2, b]
                if not abs(g - (1.0 if a == b else 0.0)) <= tol:
                    return False
        if not abs(_det3(R[k]) - 1.0) <= tol:
            return False
    return True


def _det3_py(X):  # pragma: no cover - compiled
    """The determinant of the 3×3 block of X (3, ≥3)."""
    return (
        X[0, 0] * (X[1, 1] * X[2, 2] - X[1, 2] * X[2, 1])
        - X[0, 1] * (X[1, 0] * X[2, 2] - X[1, 2] * X[2, 0])
        + X[0, 2] * (X[1, 0] * X[2, 1] - X[1, 1] * X[2, 0])
    )


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
        if not _det3(M[k]) > 0.0:
            return False
    return True


# The callees' interpreted names, as for the loops above; the compiled copies call compiled ones.
_one_stack, _det3, _rotations_ok, _exact_poses = _one_stack_py, _det3_py, _rotations_ok_py, _exact_poses_py


def _build_kernel() -> Any:
    """Compile (or load from numba's cache) the kernel.

    The loops of :mod:`~assembler_pin.statics.loops` are compiled as copies whose globals
    name the compiled callees, so the interpreted originals keep calling each other."""
    import numba  # delayed: numba's import and the cached kernel's load only when a statics runs

    jit, inlined = numba.njit(cache=True, nogil=True), numba.njit(cache=True, nogil=True, inline="always")
    scope: dict[str, Any] = {"math": math, "np": np, "__name__": __name__, "NOT_PASSED": NOT_PASSED}
    parts = (
        (inlined, "_legs", loops._legs_py),
        (inlined, "_invert", loops._invert_py),
        (inlined, "_rhs", loops._platform_rhs),
        (inlined, "_platform", loops._platform_py),
        (inlined, "_stack", loops._stack_py),
        (inlined, "_extras", loops._extras_py),
        (inlined, "_det3", _det3_py),
        (jit, "_kernel", _kernel_py),
        (jit, "_one_stack", _one_stack_py),
        (jit, "_rotations_ok", _rotations_ok_py),
        (jit, "_exact_poses", _exact_poses_py),
        (jit, "_arrays_stack", _arrays_stack_py),
        (jit, "_matrix_stack", _matrix_stack_py),
    )
    for compile_, name, func in parts:  # callees first: the callers see them compiled
        scope[name] = compile_(types.FunctionType(func.__code__, scope, func.__name__))
    global _arrays_stack, _matrix_stack
    _arrays_stack, _matrix_stack = scope["_arrays_stack"], scope["_matrix_stack"]
    return scope["_kernel"]


def kernel_available() -> bool:
    """Load the compiled kernel in this process (from numba's cache, or compiled on the first
    use after an install); True once loaded."""
    global _kernel
    if _kernel is None:
        _kernel = _build_kernel()
    return True


class _ModelArrays:
    """What the kernel reads of a model, built once per model (:func:`_model_arrays`):
    the joint centres ``bottom`` / ``top`` (n, 6, 3) in their plates' frames [m] and the
    constants ``consts`` of :data:`~assembler_pin.statics.loops.CONSTANT_NAMES`, all
    C-contiguous float arrays; ``source`` the model's config and geometry they came from."""

    __slots__ = ("bottom", "consts", "model", "source", "top")

    def __init__(self, am: AssemblerModel) -> None:
        self.model = weakref.ref(am)
        self.source = (am.config, am.geometry)
        geo = am.geometry
        self.bottom = np.ascontiguousarray(geo.bottom_in_plate, dtype=np.float64)
        self.top = np.ascontiguousarray(geo.top_in_plate, dtype=np.float64)
        self.consts = np.array(loops.constants(am.config), dtype=np.float64)


_MODEL_ARRAYS: dict[int, _ModelArrays] = {}  # by id(model); an entry is used only for that very model
_MODEL_ARRAYS_KEPT = 8


def _model_arrays(am: AssemblerModel) -> _ModelArrays:
    """The kernel's arrays of ``am``, from the cache while ``am`` keeps its config and
    geometry (the arrays of at most :data:`_MODEL_ARRAYS_KEPT` models are kept, the oldest
    dropped first; an entry holds no reference to its model)."""
    entry = _MODEL_ARRAYS.get(id(am))
    if entry is not None and entry.model() is am and entry.source[0] is am.config and entry.source[1] is am.geometry:
        return entry
    entry = _ModelArrays(am)
    _MODEL_ARRAYS.pop(id(am), None)
    while len(_MODEL_ARRAYS) >= _MODEL_ARRAYS_KEPT:
        _MODEL_ARRAYS.pop(next(iter(_MODEL_ARRAYS)), None)
    _MODEL_ARRAYS[id(am)] = entry
    return entry


def _kernel_ready(a: object, shape: tuple[int, ...]) -> bool:
    """Whether ``a`` is an array the compiled calls take as it is: a plain writeable,
    C-contiguous float64 ndarray of ``shape`` (anything else would compile another
    specialization, or is not the right input)."""
    if type(a) is not np.ndarray or a.dtype != np.float64 or a.shape != shape:
        return False
    flags = a.flags
    return flags.c_contiguous and flags.writeable


def reference_forces(am: AssemblerModel, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tests' numpy reference of :func:`closed_form_forces`:
    :func:`~assembler_pin.statics.closed_form.equilibrium` and the condition number of the legs'
    lines in each top plate's frame (:func:`~assembler_pin.statics.closed_form.line_conditions`)."""

    eq, _ = equilibrium(am, R, p)
    u_local = np.einsum("bjka,bjik->bjia", R[:, 1:], eq.u)
    lines_t = np.concatenate([u_local, cross(am.geometry.top_in_plate, u_local)], axis=-1)  # (B, n, legs, 6)
    return eq.forces, line_conditions(lines_t)[1]


def closed_form_forces(am: AssemblerModel, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Actuator forces and condition numbers of B stacks by the closed-form statics, compiled.

    Args:
        R: (B, n+1, 3, 3) plate rotations; p: (B, n+1, 3) plate positions, world [m]
            (checked by the caller).

    Returns:
        (forces (B, n, 6) [N, tension positive], condition (B, n): 1-norm condition number
        of each platform's 6×6 system; NaN for both where the system is exactly singular).
    """
    kernel_available()
    R, p = _as_kernel_input(R), _as_kernel_input(p)
    B, n = R.shape[0], am.n
    forces, condition = np.empty((B, n, 6)), np.empty((B, n))
    arrays = _model_arrays(am)
    _kernel(R, p, arrays.bottom, arrays.top, arrays.consts, forces, condition, _NO_BALL, _NO_BASE, False)
    return forces, condition


def _as_kernel_input(a: np.ndarray) -> np.ndarray:
    """``a`` as a writeable C-contiguous float64 array (a copy only where it is not one)."""
    return a if _kernel_ready(a, a.shape) else np.array(a, dtype=np.float64, order="C")


def kernel_loaded() -> bool:
    """Whether the compiled kernel is loaded in this process already (no compile, no import)."""
    return _kernel is not None


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

    """
    kernel_available()
    R, p = _as_kernel_input(R), _as_kernel_input(p)
    B, n = R.shape[0], am.n
    forces, condition = np.empty((B, n, 6)), np.empty((B, n))
    ball, base = np.empty((B, n, 6, 3)), np.empty((B, 6))
    arrays = _model_arrays(am)
    _kernel(R, p, arrays.bottom, arrays.top, arrays.consts, forces, condition, ball, base, True)
    return forces, ball, base, condition


def kernel_result(
    am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray, raise_on_singular: bool = False
) -> StaticsResult:
    """:func:`~assembler_pin.statics.engine.solve_statics` on the compiled kernel: the same
    :class:`~assembler_pin.statics.result.StaticsResult` (forces, ball forces, base wrench, condition
    numbers, the singular flag and error of :data:`~assembler_pin.statics.closed_form.CONDITION_LIMIT`),
    which the tests hold to Pinocchio's.

    Args:
        plates: plate arrays (:class:`~assembler_pin.kinematics.PlateArrays`), or the n+1
            plate poses as a float array (n+1, 4, 4), plate 0 first. The compiled call checks
            them first: plate arrays not checked yet must be finite rotations to
            :data:`ARRAYS_ROTATION_TOL`, matrices exact rotations (:data:`EXACT_ROTATION_TOL`).
            Whatever it does not pass goes through :func:`~assembler_pin.kinematics.plate_arrays`,
            which projects a rotation off by less than its tolerance and refuses the rest
            with its message.

    Raises:
        PoseError: the poses are not n+1 plate poses.
        SingularConfigurationError: with ``raise_on_singular``, a platform's condition number
            exceeds the limit.
    """
    kernel_available()
    arrays, n = _model_arrays(am), am.n
    out = (np.empty((n, 6)), np.empty(n), np.empty((n, 6, 3)), np.empty(6))
    worst = _checked_call(plates, n + 1, arrays, out)
    if worst == NOT_PASSED:  # the package's validation: refuses with its message, or checks (and projects)
        checked = plate_arrays(am, plates)
        R, p = _as_kernel_input(checked.R), _as_kernel_input(checked.p)
        worst = _arrays_stack(R, p, 0.0, arrays.bottom, arrays.top, arrays.consts, *out)
    forces, condition, ball, base = out
    singular = not worst <= CONDITION_LIMIT  # NaN counts as singular
    if singular and raise_on_singular:
        raise_singular(condition)
    return StaticsResult(forces, ball, base, condition, singular)


def _checked_call(plates: object, count: int, arrays: _ModelArrays, out: tuple[np.ndarray, ...]) -> float:
    """The compiled single-stack call on ``plates`` when they are ``count`` plate arrays or
    (count, 4, 4) matrices the kernel takes as they are and its check passes them: the
    largest condition number (NaN: singular), outputs in ``out``; else :data:`NOT_PASSED`."""
    if type(plates) is PlateArrays:
        R, p = plates.R, plates.p
        if not (_kernel_ready(R, (count, 3, 3)) and _kernel_ready(p, (count, 3))):
            return NOT_PASSED
        tol = 0.0 if plates.__dict__.get("_checked", False) else ARRAYS_ROTATION_TOL
        return _arrays_stack(R, p, tol, arrays.bottom, arrays.top, arrays.consts, *out)
    if _kernel_ready(plates, (count, 4, 4)):
        return _matrix_stack(plates, EXACT_ROTATION_TOL, arrays.bottom, arrays.top, arrays.consts, *out)
    return NOT_PASSED
