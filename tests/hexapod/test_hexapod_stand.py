"""The hexapod's equilibrium held to independent computations: the tests' own minimization of
the whole structure's potential (written here, derivatives by complex steps, scipy's
trust-region Newton), the statics of the whole machine (its weight and its centre of mass
against the feet's wrenches) and the support polygon by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize

import assembler_pin as ap
from assembler_pin.exceptions import HexapodError, PoseError
from assembler_pin.hexapod import ring_stacks, stand


def _model(platforms: int = 2, stiffness: float = 2e4) -> ap.AssemblerModel:
    """A model without tool payload (the body is the load), soft legs: large deflections."""
    cfg = {"platforms": platforms, "payload": {"mass": 0.0}, "leg": {"stiffness": stiffness}}
    return ap.AssemblerModel.from_config(cfg)


def _exp(w):
    """exp of the skew matrix of w by its power series: analytic, so complex steps go through."""
    K = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    out, term = np.eye(3, dtype=K.dtype), np.eye(3, dtype=K.dtype)
    for m in range(1, 20):
        term = term @ K / m
        out = out + term
    return out


class Potential:
    """The whole hexapod's potential over the body's motion (at its centre of mass) and every
    free plate's, written from the geometry alone: legs ½ k (L − L0)², weights m g z."""

    def __init__(self, am, stacks, rest, body_mass, com, free_feet=()):
        self.am, self.rest, self.mass, self.com = am, rest, body_mass, np.asarray(com, float)
        self.R0 = np.array([s.R for s in stacks])
        self.p0 = np.array([s.p for s in stacks])
        self.free = [(i, j) for i in range(len(stacks)) for j in range(am.n) if j > 0 or i in free_feet]

    def plates(self, x):
        dtype = x.dtype
        R, p = self.R0.astype(dtype), self.p0.astype(dtype)
        turn = _exp(x[3:6])
        com = self.com + x[:3]
        R[:, -1] = turn @ self.R0[:, -1]
        p[:, -1] = com + (self.p0[:, -1] - self.com) @ turn.T
        for m, (i, j) in enumerate(self.free):
            y = x[6 + 6 * m : 12 + 6 * m]
            R[i, j] = _exp(y[3:]) @ self.R0[i, j]
            p[i, j] = self.p0[i, j] + y[:3]
        return R, p, com

    def legs(self, R, p):
        geo = self.am.geometry
        b = p[:, :-1, None, :] + np.einsum("knab,nlb->knla", R[:, :-1], geo.bottom_in_plate)
        t = p[:, 1:, None, :] + np.einsum("knab,nlb->knla", R[:, 1:], geo.top_in_plate)
        d = t - b
        L = np.sqrt((d * d).sum(-1))
        return b, t, d / L[..., None], L

    def __call__(self, x):
        cfg = self.am.config
        leg, g = cfg.leg, cfg.gravity
        R, p, com = self.plates(x)
        b, t, u, L = self.legs(R, p)
        V = 0.5 * leg.stiffness * ((L - self.rest) ** 2).sum()
        V = V + g * cfg.plate.mass * p[..., 2].sum() + g * self.mass * com[2]
        V = V + g * leg.motor_mass * (b + leg.motor_com * u)[..., 2].sum()
        return V + g * leg.shaft_mass * (t - leg.shaft_com * u)[..., 2].sum()

    def gradient(self, x, h=1e-30):
        out = np.empty(len(x))
        for j in range(len(x)):
            y = x.astype(complex)
            y[j] += 1j * h
            out[j] = self(y).imag / h
        return out

    def hessian(self, x, h=1e-7):
        H = np.empty((len(x), len(x)))
        for j in range(len(x)):
            e = np.zeros(len(x))
            e[j] = h
            H[:, j] = (self.gradient(x + e) - self.gradient(x - e)) / (2 * h)
        return 0.5 * (H + H.T)

    def minimum(self):
        x0 = np.zeros(6 + 6 * len(self.free))
        x = minimize(self, x0, jac=self.gradient, hess=self.hessian, method="trust-exact", options={"gtol": 1e-9}).x
        for _ in range(3):  # its last digits: Newton's steps on the gradient, past the value's round-off
            x = x - np.linalg.solve(self.hessian(x), self.gradient(x))
        assert np.abs(self.gradient(x)).max() < 1e-8
        return x

    def forces(self, x):
        R, p, _ = self.plates(x)
        return self.am.config.leg.stiffness * (self.legs(R, p)[3] - self.rest)


def _lengths(am, stacks, spread, seed=3):
    own = np.array([ap.kinematics.leg_state(am, s).lengths for s in stacks])
    return own + np.random.default_rng(seed).uniform(-spread, spread, own.shape)


def test_welded_forces_are_the_minimum_of_the_whole_structures_potential():
    """Three stacks of two platforms, soft legs commanded 2 mm off their poses' lengths (tens of
    mm of motion: far from linear); the Newton answer and the tests' own minimization agree."""
    am = _model()
    stacks = ring_stacks(am, 3, 0.5)
    com = stacks[0].p[-1] * [0, 0, 1] + [0.03, -0.02, 0.12]
    rest = _lengths(am, stacks, 2e-3)
    got = stand(am, stacks, 15.0, com, lengths=rest)
    pot = Potential(am, stacks, rest, 15.0, com)
    x = pot.minimum()
    assert got.converged and got.stable
    np.testing.assert_allclose(got.forces, pot.forces(x), atol=1e-6)
    np.testing.assert_allclose(got.body_displacement[:3], x[:3], atol=1e-10)
    assert np.abs(got.body_displacement[:3]).max() > 1e-3  # a large displacement indeed
    p = pot.plates(x)[1]
    np.testing.assert_allclose(got.plates[..., :3, 3], p, atol=1e-10)
    # the ground's wrench on each foot: the potential's gradient in that foot's motion
    feet = Potential(am, stacks, rest, 15.0, com, free_feet=(0, 1, 2))
    xf = np.zeros(6 + 6 * len(feet.free))
    where = {pair: m for m, pair in enumerate(feet.free)}
    xf[:6] = x[:6]
    for m, pair in enumerate(pot.free):
        xf[6 + 6 * where[pair] : 12 + 6 * where[pair]] = x[6 + 6 * m : 12 + 6 * m]
    grad = feet.gradient(xf)
    for i in range(3):
        m = where[(i, 0)]
        np.testing.assert_allclose(got.foot_wrenches[i], grad[6 + 6 * m : 12 + 6 * m], atol=1e-6)


def test_a_lifted_foot_hangs_where_the_potential_is_least():
    """Resting feet, the body far over one side: the feet that would pull lift off, and the
    structure with those stacks hanging is the tests' own minimum with their feet free."""
    am = _model(platforms=1, stiffness=1e5)
    stacks = ring_stacks(am, 4, 0.5)
    com = np.array([0.55, 0.0, stacks[0].p[-1, 2] + 0.05])
    got = stand(am, stacks, 30.0, com, feet="resting")
    lifted = tuple(int(i) for i in np.flatnonzero(got.lifted))
    assert lifted == (2,) and got.converged
    pot = Potential(am, stacks, got.lengths, 30.0, com, free_feet=lifted)
    x = pot.minimum()
    np.testing.assert_allclose(got.forces, pot.forces(x), atol=1e-6)
    assert got.plates[2, 0, 2, 3] > 0  # off the floor
    assert np.all(got.foot_wrenches[2] == 0) and np.all(got.foot_wrenches[[0, 1, 3], 2] > 0)


def _hand_weight(am, k, body_mass):
    cfg = am.config
    per_stack = (am.n + 1) * cfg.plate.mass + 6 * am.n * (cfg.leg.motor_mass + cfg.leg.shaft_mass)
    return (body_mass + k * per_stack) * cfg.gravity


@pytest.mark.parametrize("feet", ["welded", "resting"])
def test_feet_carry_the_whole_machine_and_its_centre_of_mass(feet):
    """Σ of the foot wrenches is the machine's weight counted by hand; their moment about the
    world origin puts the centre of mass where the masses put it."""
    am = _model(platforms=3, stiffness=1e6)
    stacks = ring_stacks(am, 6, 0.6)
    com = np.array([0.05, 0.02, stacks[0].p[-1, 2] + 0.1])
    got = stand(am, stacks, 40.0, com, feet=feet)
    assert got.feasible, got.violations
    f = got.foot_wrenches[:, :3]
    m = got.foot_wrenches[:, 3:] + np.cross(got.plates[:, 0, :3, 3], f)
    weight = _hand_weight(am, 6, 40.0)
    np.testing.assert_allclose(f.sum(0), [0, 0, weight], atol=1e-8)
    assert got.mass * am.config.gravity == pytest.approx(weight, rel=1e-12)
    # moment of the ground's forces = − moment of the weight: (x_c, y_c) from the wrenches
    M = m.sum(0)
    np.testing.assert_allclose([-M[1] / weight, M[0] / weight], got.com[:2], atol=1e-10)


def test_the_stability_margin_of_a_hexagon_by_hand():
    """Six feet on a circle of radius R: the support polygon is the hexagon of the feet grown
    by the plate radius r; with the centre of mass at x on the axis through a foot, the nearest
    edges are the two whose normals are ±30°: margin = r + (R − x) cos 30°, and x itself is the
    ground's centre of pressure (from the wrenches)."""
    am = _model(platforms=3, stiffness=1e6)
    R, r = 0.6, am.config.plate.radius
    stacks = ring_stacks(am, 6, R)
    for offset in (0.0, 0.1, 0.3):
        com = np.array([offset, 0.0, stacks[0].p[-1, 2] + 0.1])
        got = stand(am, stacks, 60.0, com, feet="resting")
        w = got.foot_wrenches
        x = ((w[:, 2] * got.plates[:, 0, 0, 3]).sum() - w[:, 4].sum()) / w[:, 2].sum()
        assert got.stability_margin_m == pytest.approx(r + (R - x) * math.cos(math.pi / 6), abs=1e-12)
    centred = stand(am, stacks, 60.0, [0, 0, stacks[0].p[-1, 2] + 0.1], feet="resting")
    np.testing.assert_allclose(centred.foot_wrenches[:, 2], _hand_weight(am, 6, 60.0) / 6, rtol=1e-9)


def test_tipping_slipping_and_limits_are_violations_not_errors():
    am = _model(platforms=1, stiffness=1e6)
    stacks = ring_stacks(am, 3, 0.4)
    top = stacks[0].p[-1, 2]
    tipping = stand(am, stacks, 50.0, [0.9, 0.0, top + 0.05], feet="resting")
    assert not tipping.feasible and tipping.stability_margin_m < 0
    assert any("tips" in v for v in tipping.violations)
    off = _lengths(am, stacks, 3e-4)
    slipping = stand(am, stacks, 5.0, [0.0, 0.0, top], lengths=off, feet="resting", friction=0.01)
    assert not slipping.feasible and any("slips" in v for v in slipping.violations)
    heavy = stand(am, stacks, 5000.0, [0.0, 0.0, top])
    assert not heavy.feasible and heavy.max_abs_force > am.config.leg.max_compression
    assert any("compression" in v for v in heavy.violations)
    margin = stand(am, stacks, 5.0, [0.0, 0.0, top], feet="resting", min_margin=1.0)
    assert not margin.feasible and any("min_margin" in v for v in margin.violations)


def test_resting_and_welded_agree_when_every_foot_pushes():
    am = _model(platforms=2, stiffness=1e6)
    stacks = ring_stacks(am, 6, 0.6)
    com = [0.02, 0.0, stacks[0].p[-1, 2] + 0.1]
    welded, resting = stand(am, stacks, 20.0, com), stand(am, stacks, 20.0, com, feet="resting")
    np.testing.assert_array_equal(welded.forces, resting.forces)
    assert math.isnan(welded.stability_margin_m) and resting.stability_margin_m > 0


@pytest.mark.parametrize(
    ("kwargs", "error"),
    [
        ({"feet": "glued"}, HexapodError),
        ({"body_mass": math.nan}, HexapodError),
        ({"body_mass": -1.0}, HexapodError),
        ({"body_com": [0, 0]}, HexapodError),
        ({"body_com": [0, math.inf, 0]}, HexapodError),
        ({"lengths": np.zeros((2, 1, 6))}, HexapodError),
        ({"lengths": np.full((3, 1, 6), math.nan)}, HexapodError),
        ({"friction": -0.1}, HexapodError),
        ({"stacks": []}, HexapodError),
        ({"stacks": "stacks"}, HexapodError),
        ({"stacks": [[np.eye(4)]]}, PoseError),
    ],
)
def test_malformed_input_is_refused(kwargs, error):
    am = _model(platforms=1)
    args = {"stacks": ring_stacks(am, 3, 0.4), "body_mass": 1.0, "body_com": [0, 0, 0.3]} | kwargs
    with pytest.raises(error):
        stand(am, **args)


def test_resting_feet_must_be_level_on_one_floor():
    am = _model(platforms=1)
    stacks = ring_stacks(am, 3, 0.4)
    raised = [ap.kinematics.PlateArrays(s.R, s.p + np.array([0, 0, 0.01 * i])) for i, s in enumerate(stacks)]
    with pytest.raises(HexapodError, match="level"):
        stand(am, raised, 1.0, [0, 0, 0.3], feet="resting")
    assert stand(am, raised, 1.0, [0, 0, 0.3]).converged  # welded: any heights
