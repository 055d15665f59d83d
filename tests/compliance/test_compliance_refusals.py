"""Refusals of the compliant truss's inputs: one line naming the key, before any work."""

from __future__ import annotations

import numpy as np
import pytest

import assembler_pin as ap
from assembler_pin.compliance import MAX_WRENCH, compensated_lengths, loaded_pose
from assembler_pin.compliance.scaling import stiffness_scaling
from assembler_pin.config.bounds import BOUNDS
from assembler_pin.exceptions import LoadError, OptionsError


@pytest.mark.parametrize("scale", [1.0000001, 10.0, 1e300])
def test_an_absurd_wrench_is_refused_naming_its_bound(am, scale):
    lengths = ap.kinematics.leg_state(am, am.home).lengths
    with pytest.raises(LoadError, match=r"wrench.*\[0, 1e\+06\]"):
        loaded_pose(am, lengths, wrench=[0, 0, -MAX_WRENCH * scale, 0, 0, 0])
    assert MAX_WRENCH == BOUNDS["elastic.wrench"].high


@pytest.mark.parametrize("tol", [0.0, -1e-9, float("nan"), float("inf"), 1.0, "1e-9", True])
def test_bad_newton_tolerances_are_refused(am, tol):
    with pytest.raises(LoadError, match="tol"):
        ap.stiffness(am, am.home, tol=tol)
    with pytest.raises(LoadError, match="tol"):
        loaded_pose(am, ap.kinematics.leg_state(am, am.home).lengths, tol=tol)


@pytest.mark.parametrize("value", [0, -3, 10**9, 2.5, float("nan")])
def test_bad_iteration_counts_are_refused(am, value):
    with pytest.raises(LoadError, match="max_iterations"):
        loaded_pose(am, ap.kinematics.leg_state(am, am.home).lengths, max_iterations=value)


@pytest.mark.parametrize("value", [0.0, 1e-13, 1e-2, float("nan"), None])
def test_bad_compensation_tolerances_are_refused(am, value):
    with pytest.raises(LoadError, match="tolerance"):
        compensated_lengths(am, am.home, tolerance=value)


@pytest.mark.parametrize("value", [0, 65, 2.0, -1])
def test_bad_scaling_ranges_are_refused(value):
    with pytest.raises(OptionsError, match="max_platforms"):
        stiffness_scaling(max_platforms=value)


def test_the_defaults_stay_inside_the_bounds(am):
    lengths = ap.kinematics.leg_state(am, am.home).lengths
    assert loaded_pose(am, lengths, wrench=np.r_[0, 0, -MAX_WRENCH / 1e4, 0, 0, 0]).success
    assert compensated_lengths(am, am.home, tolerance=1e-12).success
