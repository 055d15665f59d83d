"""Answers that used to be silently wrong, re-checked against an independent computation:
a result returned with ``success`` true holds up whatever allowed option produced it."""

from __future__ import annotations

import numpy as np
import pytest

import assembler_pin as ap
from assembler_pin.config.bounds import BOUNDS


@pytest.mark.parametrize("tol", [BOUNDS["elastic.tol"].high, 1e-6, 1e-9])
def test_stiffness_forces_hold_at_every_allowed_tolerance(am, tol):
    """The elastic forces are those of the loaded pose, never the start's zero: they agree with
    the tightest solve and balance the rigid statics' load (the home pose under gravity)."""
    tight = ap.stiffness(am, am.home, tol=BOUNDS["elastic.tol"].low * 1e3)
    got = ap.stiffness(am, am.home, tol=tol)
    assert got.success and tight.success
    rigid = ap.solve_statics(am, am.home).forces
    assert np.abs(got.forces).max() > 0.5 * np.abs(rigid).max()
    assert np.abs(got.forces - tight.forces).max() < 1e-2 * max(1.0, np.abs(rigid).max())


@pytest.mark.parametrize("scale", [1.0, 1e2, BOUNDS["dynamics.motion"].high])
def test_inverse_dynamics_within_the_motion_bound_is_finite(am, scale):
    """Every motion the bound allows gives finite forces (beyond it: refused, see the corpus)."""
    twists = np.full((am.n, 6), scale)
    result = ap.inverse_dynamics(am, am.home, twists, np.full((am.n, 6), scale))
    assert np.isfinite(result.forces).all() or result.singular
