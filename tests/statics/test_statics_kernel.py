"""The compiled single-stack calls of the statics kernel: their pose checks refuse exactly
what :func:`~assembler_pin.kinematics.plate_arrays` refuses, with its message, and every
answer they give is Pinocchio's statics (:func:`~assembler_pin.statics.pinocchio_statics.solve_statics_pinocchio`).

The interpreted loops (the numpy-free path of ``statics --home``) are held to Pinocchio on
moved and turned stacks too, since the compiled kernel is compiled from the same source.
"""

from __future__ import annotations

import gc
import importlib.util
import weakref

import numpy as np
import pinocchio as pin
import pytest

from assembler_pin.exceptions import PoseError
from assembler_pin.kinematics import ORTHONORMAL_TOL, PlateArrays, plate_arrays
from assembler_pin.model import AssemblerModel
from assembler_pin.statics import kernel as statics_kernel
from assembler_pin.statics import solve_statics_pinocchio
from assembler_pin.statics.loops import Grid, closed_form_pure, constants

pytestmark = pytest.mark.skipif(importlib.util.find_spec("numba") is None, reason="no numba")

FIELDS = ("forces", "ball_forces", "base_wrench")


def _stack(am: AssemblerModel, seed: int) -> PlateArrays:
    """Checked plate arrays: each plate of the home pose moved by a random twist (±1 cm,
    ±0.05 rad), the whole stack on a random base pose."""
    rng = np.random.default_rng(seed)
    base = pin.SE3(pin.exp3(rng.uniform(-0.3, 0.3, 3)), rng.uniform(-0.5, 0.5, 3))
    poses = []
    for k, m in enumerate(am.home):
        move = pin.exp6(np.concatenate([rng.uniform(-0.01, 0.01, 3), rng.uniform(-0.05, 0.05, 3)]))
        poses.append(base * (m * move if k else m))
    return plate_arrays(am, poses)


def _off_tolerance(R: np.ndarray) -> float:
    """The forces' tolerance [N] for rotations R (m, 3, 3) that are not exact: the kernel uses
    them as given, Pinocchio's statics as rotations (projected), which moves forces of
    ~100 N by ~100 N × |RᵀR − I|."""
    err = np.abs(np.matmul(R.transpose(0, 2, 1), R) - np.eye(3)).max()
    return 1e-10 + 1e3 * err


def _fresh(R: np.ndarray, p: np.ndarray) -> PlateArrays:
    """Plate arrays nothing has checked yet (copies of R and p)."""
    return PlateArrays(np.array(R), np.array(p))


def _assert_is_pinocchios(am: AssemblerModel, got, plates, atol: float = 1e-10) -> None:
    """``got`` against Pinocchio's statics of ``plates``, to ``atol`` [N, N·m]."""
    ref = solve_statics_pinocchio(am, plates)
    for field in FIELDS:
        np.testing.assert_allclose(getattr(got, field), getattr(ref, field), atol=atol, rtol=0, err_msg=field)
    np.testing.assert_allclose(got.condition, ref.condition, rtol=max(1e-9, atol))
    assert got.singular is ref.singular


@pytest.fixture(scope="module")
def am4() -> AssemblerModel:
    return AssemblerModel.from_config({"platforms": 4})


def _hostile_arrays(pa: PlateArrays) -> dict[str, tuple]:
    """(R, p) pairs plate_arrays refuses, one per kind of fault."""
    R, p = pa.R, pa.p
    out: dict[str, tuple] = {}
    for what, k, value in (("nan R", 2, np.nan), ("inf R", 4, -np.inf)):
        bad = R.copy()
        bad[k, 1, 2] = value
        out[what] = (bad, p)
    bad_p = p.copy()
    bad_p[3, 0] = np.inf
    out["inf p"] = (R, bad_p)
    scaled = R.copy()
    scaled[1] *= 1 + 1e-6  # not orthonormal
    out["scaled"] = (scaled, p)
    mirrored = R.copy()
    mirrored[3, :, 0] *= -1  # orthonormal, det -1
    out["mirrored"] = (mirrored, p)
    out["one plate short"] = (R[:-1], p[:-1])
    out["p of 4 columns"] = (R, np.hstack([p, np.ones((len(p), 1))]))
    out["integer R"] = (np.rint(R).astype(int), p)
    return out


def test_kernel_result_refuses_what_plate_arrays_refuses_with_its_message(am4):
    """Plate arrays not checked yet: each malformed one is refused by the kernel's call with
    plate_arrays' own message (the compiled check lets none through)."""
    for what, (R, p) in _hostile_arrays(_stack(am4, 1)).items():
        with pytest.raises(PoseError) as expected:
            plate_arrays(am4, _fresh(R, p))
        with pytest.raises(PoseError) as got:
            statics_kernel.kernel_result(am4, _fresh(R, p))
        assert str(got.value) == str(expected.value), what


def test_unchecked_arrays_near_the_tolerance_go_through_plate_arrays(am4):
    """A rotation off by more than the compiled check passes but less than ORTHONORMAL_TOL is
    accepted (by plate_arrays, as given), and answered as by Pinocchio; one just past
    ORTHONORMAL_TOL is refused."""
    pa = _stack(am4, 2)
    for scale, accepted in ((1 + 0.35 * ORTHONORMAL_TOL, True), (1 + 0.6 * ORTHONORMAL_TOL, False)):
        R = pa.R.copy()
        R[2, :, 0] *= scale  # |RᵀR − I| ≈ 2 (scale − 1), det ≈ scale
        assert np.abs(R[2].T @ R[2] - np.eye(3)).max() > statics_kernel.ARRAYS_ROTATION_TOL
        if accepted:
            got = statics_kernel.kernel_result(am4, _fresh(R, pa.p))
            _assert_is_pinocchios(am4, got, _fresh(R, pa.p), _off_tolerance(R))
        else:
            with pytest.raises(PoseError, match="is not a rotation"):
                statics_kernel.kernel_result(am4, _fresh(R, pa.p))


def test_compiled_check_agrees_with_plate_arrays_on_perturbed_rotations(am4):
    """Random perturbations of every size around the tolerance: the kernel's call accepts
    exactly the arrays plate_arrays accepts, and then answers as Pinocchio."""
    pa = _stack(am4, 3)
    rng = np.random.default_rng(0)
    outcomes = set()
    for size in np.logspace(-11, -8, 40):
        R = pa.R.copy()
        R[rng.integers(len(R))] += rng.normal(0.0, size, (3, 3))
        try:
            plate_arrays(am4, _fresh(R, pa.p))
        except PoseError as refused:
            with pytest.raises(PoseError) as got:
                statics_kernel.kernel_result(am4, _fresh(R, pa.p))
            assert str(got.value) == str(refused)
            outcomes.add("refused")
        else:
            got = statics_kernel.kernel_result(am4, _fresh(R, pa.p))
            _assert_is_pinocchios(am4, got, _fresh(R, pa.p), _off_tolerance(R))
            outcomes.add("accepted")
    assert outcomes == {"accepted", "refused"}


def test_unchecked_and_checked_arrays_give_pinocchios_statics(am4):
    """Fresh plate arrays (compiled check), the same arrays once checked (no check) and
    their 4×4 matrices (compiled exact-pose check): one answer, Pinocchio's."""
    pa = _stack(am4, 4)
    fresh = _fresh(pa.R, pa.p)
    for plates in (fresh, plate_arrays(am4, fresh), pa.as_matrices()):
        _assert_is_pinocchios(am4, statics_kernel.kernel_result(am4, plates), pa)


def test_odd_arrays_are_copied_not_compiled_for(am4):
    """Read-only, Fortran-ordered and float32 (positions) inputs give the answer of the
    plain arrays, with no compiled specialization added for them."""
    pa = _stack(am4, 5)
    statics_kernel.kernel_result(am4, pa)
    statics_kernel.kernel_result(am4, pa.as_matrices())
    statics_kernel.closed_form_forces(am4, pa.R[None], pa.p[None])
    calls = (statics_kernel._arrays_stack, statics_kernel._matrix_stack, statics_kernel._kernel)
    compiled = [len(call.signatures) for call in calls]
    readonly_R, readonly_p = pa.R.copy(), pa.p.copy()
    readonly_R.flags.writeable = readonly_p.flags.writeable = False
    matrices = pa.as_matrices()
    matrices.flags.writeable = False
    odd = {
        "read-only": PlateArrays(readonly_R, readonly_p),
        "fortran": PlateArrays(np.asfortranarray(pa.R), np.asfortranarray(pa.p)),
        "read-only matrices": matrices,
        "fortran matrices": np.asfortranarray(pa.as_matrices()),
    }
    for what, plates in odd.items():
        got, ref = statics_kernel.kernel_result(am4, plates), statics_kernel.kernel_result(am4, pa)
        for field in FIELDS:
            np.testing.assert_allclose(getattr(got, field), getattr(ref, field), atol=1e-12, rtol=0, err_msg=what)
    p32 = PlateArrays(pa.R, pa.p.astype(np.float32))
    _assert_is_pinocchios(am4, statics_kernel.kernel_result(am4, p32), plate_arrays(am4, p32))
    forces, _ = statics_kernel.closed_form_forces(am4, readonly_R[None], readonly_p[None])
    np.testing.assert_allclose(forces[0], solve_statics_pinocchio(am4, pa).forces, atol=1e-10, rtol=0)
    assert [len(call.signatures) for call in calls] == compiled


def test_models_of_every_size_in_turn_get_their_own_arrays():
    """Models of different sizes and payloads called in turn: each answer is its own
    model's (Pinocchio's), and the kernel's cache keeps no model alive."""
    models = [
        AssemblerModel.from_config({"platforms": 2}),
        AssemblerModel.from_config({"platforms": 3}),
        AssemblerModel.from_config({"platforms": 3, "payload": {"mass": 1.5, "offset": 0.1}}),
    ]
    stacks = [_stack(m, 10 + k) for k, m in enumerate(models)]
    for _ in range(2):
        for k, pa in enumerate(stacks):
            _assert_is_pinocchios(models[k], statics_kernel.kernel_result(models[k], pa), pa)
    gone = weakref.ref(models.pop())
    gc.collect()
    assert gone() is None


def test_a_singular_stack_is_flagged_from_every_input(am4):
    """The octahedral singularity (a platform turned 90° about its axis): flagged singular
    from fresh arrays and from 4×4 matrices, as by Pinocchio."""
    poses = list(am4.home)
    turn = pin.SE3(pin.exp3(np.array([0.0, 0.0, np.pi / 2])), np.zeros(3))
    poses[2] = poses[2] * turn
    poses[3] = poses[3] * turn
    poses[4] = poses[4] * turn
    pa = plate_arrays(am4, poses)
    assert solve_statics_pinocchio(am4, pa).singular
    for plates in (_fresh(pa.R, pa.p), pa.as_matrices()):
        assert statics_kernel.kernel_result(am4, plates).singular


@pytest.mark.parametrize("n", [1, 4])
def test_interpreted_loops_are_pinocchios_statics(n):
    """The loops run interpreted on Grids (no numpy) on moved and turned stacks: forces,
    ball forces, base wrench and condition numbers against Pinocchio's statics."""
    am = AssemblerModel.from_config({"platforms": n})
    geo = am.geometry
    for seed in range(2):
        pa = _stack(am, 20 + seed)
        R, p = Grid((1, n + 1, 3, 3), pa.R.ravel().tolist()), Grid((1, n + 1, 3), pa.p.ravel().tolist())
        bottom = Grid((n, 6, 3), geo.bottom_in_plate.ravel().tolist())
        top = Grid((n, 6, 3), geo.top_in_plate.ravel().tolist())
        forces, condition, ball, base = closed_form_pure(R, p, bottom, top, constants(am.config))
        ref = solve_statics_pinocchio(am, pa)
        got = {"forces": forces.nested()[0], "ball_forces": ball.nested()[0], "base_wrench": base.data}
        for field in FIELDS:
            np.testing.assert_allclose(got[field], getattr(ref, field), atol=1e-10, rtol=0, err_msg=field)
        np.testing.assert_allclose(condition.data, ref.condition, rtol=1e-9)
