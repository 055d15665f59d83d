"""The force-optimal commands stand the machine with the chosen forces, and ``∂F/∂L_cmd``
is the finite difference of the stand itself."""

from __future__ import annotations

import numpy as np
import pytest

import assembler_pin as ap
from assembler_pin.hexapod import force_optimal_commands, length_sensitivity, ring_stacks, stand


def _machine(platforms=3, count=6):
    am = ap.AssemblerModel.from_config({"platforms": platforms, "payload": {"mass": 0.0}})
    stacks = ring_stacks(am, count, 0.6)
    return am, stacks, np.array([0.05, -0.03, stacks[0].p[-1, 2] + 0.1])


def test_the_commanded_lengths_stand_with_the_chosen_forces():
    """The linear program's distribution, commanded: the whole structure's equilibrium (the
    Newton solve of the stand, not the program) is at the given poses with those forces; the
    poses' own lengths give another, worse, distribution."""
    am, stacks, com = _machine()
    cmd = force_optimal_commands(am, stacks, 30.0, com)
    assert cmd.success, cmd.message
    got = stand(am, stacks, 30.0, com, lengths=cmd.lengths)
    assert got.feasible and np.abs(got.forces - cmd.forces).max() <= 1e-6
    assert np.abs(got.body_displacement).max() <= 1e-10
    np.testing.assert_allclose(got.plates[..., :3, 3], [s.p for s in stacks], atol=1e-10)
    own = stand(am, stacks, 30.0, com)
    assert own.max_abs_force > cmd.max_abs_force


@pytest.mark.parametrize("feet", ["welded", "resting"])
def test_the_sensitivity_is_the_stands_finite_difference(feet):
    am, stacks, com = _machine(platforms=2, count=3)
    base = stand(am, stacks, 10.0, com, feet=feet)
    S = length_sensitivity(am, base)
    h = 1e-7
    for b in (0, 7, 20, 35):
        L = base.lengths.copy().ravel()
        L[b] += h
        up = stand(am, stacks, 10.0, com, lengths=L.reshape(base.lengths.shape), feet=feet)
        L[b] -= 2 * h
        down = stand(am, stacks, 10.0, com, lengths=L.reshape(base.lengths.shape), feet=feet)
        fd = (up.forces - down.forces).ravel() / (2 * h)
        np.testing.assert_allclose(S[:, b], fd, atol=1e-6 * np.abs(fd).max())
    # a leg's own command moves its force by less than its spring alone would
    assert np.all(np.diag(S) < 0) and np.all(np.diag(S) > -am.config.leg.stiffness)


@pytest.mark.parametrize("feet", ["welded", "resting"])
def test_the_capacity_is_where_a_limit_breaks(feet):
    """The mass found stands, rtol above it does not; the forces are affine in the mass to
    first order, so two stands predict the same capacity (the first leg to reach its limit);
    and no fixed commands carry more than the linear program's best distribution."""
    from assembler_pin.hexapod import hexapod_capacity

    am, stacks, com = _machine()
    got = hexapod_capacity(am, stacks, com, feet=feet, rtol=1e-6)
    assert got.at_capacity.feasible and got.above is not None and not got.above.feasible
    assert got.above.body_mass - got.mass <= 1e-6 * got.above.body_mass
    assert "leg.max_compression" in got.limit
    F0, F1 = (stand(am, stacks, m, com, feet=feet).forces for m in (0.0, 10.0))
    slope = (F1 - F0) / 10.0
    limit = np.where(slope < 0, (-am.config.leg.max_compression - F0) / slope, np.inf)
    limit = np.minimum(limit, np.where(slope > 0, (am.config.leg.max_tension - F0) / slope, np.inf))
    assert got.mass == pytest.approx(limit.min(), rel=2e-3)
    assert got.mass <= ap.walk.macro_capacity(am, stacks, com)[0] * (1 + 1e-3)


def test_the_smallest_sum_of_squares_among_the_min_max_distributions():
    """Same max|F| as the linear program, no larger Σ F², stood exactly; and the KKT conditions
    of min Σ F² over the EE wrenches u, F = F0 + N u (each stack's held_equilibrium), Σ u = the
    body's weight, |F| ≤ max|F|: 2 Nᵀ F = Bᵀ λ + Σ μ (∓N rows of the legs at ±max|F|), μ ≥ 0,
    solved here by bounded least squares to a residual of rounding."""
    from scipy.optimize import lsq_linear

    from assembler_pin.common.linalg import skew
    from assembler_pin.supports.choice import held_equilibrium

    am, stacks, com = _machine(platforms=2, count=3)
    lp = force_optimal_commands(am, stacks, 10.0, com)
    qp = force_optimal_commands(am, stacks, 10.0, com, smallest=True)
    assert qp.success and "SLSQP" in qp.message
    assert qp.max_abs_force == pytest.approx(lp.max_abs_force, rel=1e-8)
    assert (qp.forces**2).sum() <= (lp.forces**2).sum() + 1e-9
    got = stand(am, stacks, 10.0, com, lengths=qp.lengths)
    assert np.abs(got.forces - qp.forces).max() <= 1e-6
    N = np.zeros((36, 18))
    B = np.zeros((6, 18))
    for i, pa in enumerate(stacks):
        N[12 * i : 12 * i + 12, 6 * i : 6 * i + 6] = held_equilibrium(am, pa, "both").null.reshape(12, 6)
        B[:, 6 * i : 6 * i + 6] = np.eye(6)
        B[3:, 6 * i : 6 * i + 3] = skew(pa.p[-1])
    F = qp.forces.ravel()
    peak = np.abs(F).max()
    active = np.flatnonzero(np.abs(F) >= peak * (1 - 1e-7))
    normals = N[active] * np.sign(F[active])[:, None]  # the outward normal of |F_a| ≤ peak
    A = np.hstack([B.T, -B.T, -normals.T])  # λ = λ+ − λ−, μ ≥ 0: gradient + Σ μ normals = Bᵀ λ
    fit = lsq_linear(A, 2.0 * N.T @ F, bounds=(0.0, np.inf), tol=1e-14, lsmr_tol="auto")
    assert np.abs(A @ fit.x - 2.0 * N.T @ F).max() <= 1e-6 * np.abs(2.0 * N.T @ F).max()
