"""Ω (paper eq. 10) and the motion term: the one definition, held to the paper's formula
written out here (forces by free bodies, λ by eq. 9, leg lengths from the design anchors),
and the only place in the package where Ω is written."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from checks import design_anchors, design_forces

import assembler_pin
from assembler_pin import evaluate_state
from assembler_pin.optimize import MotionTerm
from assembler_pin.optimize.objective import motion_cost, objective_value, omega


def _paper_lambda(cfg, plates) -> np.ndarray:
    """Paper eq. 9: λ_i = acos(â·ĉ), â along p_i - p_{i-1}, ĉ along p_i^rest - p_{i-1}, the
    rest position of plate i straight above plate i-1 at the home height."""
    out = []
    for i in range(1, cfg.platforms + 1):
        a = plates.p[i] - plates.p[i - 1]
        c = plates.R[i - 1] @ np.array([0.0, 0.0, cfg.home_height])
        cos = a @ c / (np.linalg.norm(a) * np.linalg.norm(c))
        out.append(np.arccos(np.clip(cos, -1.0, 1.0)))
    return np.array(out)


def _paper_omega(cfg, plates, w1: float, w2: float) -> float:
    """Paper eq. 10: w1·max|F(L_1:6n)| + w2·sqrt(Σ λ_i²)."""
    forces = design_forces(cfg, plates)
    return float(w1 * np.max(np.abs(forces)) + w2 * np.sqrt(np.sum(_paper_lambda(cfg, plates) ** 2)))


def _design_lengths(cfg, plates) -> np.ndarray:
    """(n, 6) pin-to-pin leg lengths from the design anchors [m]."""
    out = np.zeros((cfg.platforms, 6))
    for j in range(cfg.platforms):
        bottom, top = design_anchors(cfg, j)
        b = bottom @ plates.R[j].T + plates.p[j]
        t = top @ plates.R[j + 1].T + plates.p[j + 1]
        out[j] = np.linalg.norm(t - b, axis=1)
    return out


@pytest.mark.parametrize(("pose", "w1", "w2"), [(0, 1.0, 1.0), (3, 0.5, 20.0), (6, 2.0, 0.0)])
def test_omega_of_a_state_is_the_papers_formula(am, random_poses, pose, w1, w2):
    _, plates = random_poses[pose]
    state = evaluate_state(am, plates)
    assert objective_value(am, state, w1, w2) == pytest.approx(_paper_omega(am.config, plates, w1, w2), rel=1e-9)


def test_omega_adds_its_two_weighted_terms():
    angles = np.array([0.03, -0.04, 0.0, 0.12])
    assert omega(10.0, angles, 1.0, 1.0) == pytest.approx(10.0 + 0.13, rel=1e-12)
    assert omega(10.0, angles, 0.5, 2.0) == pytest.approx(5.0 + 0.26, rel=1e-12)
    assert omega(10.0, np.zeros(4), 1.0, 5.0) == 10.0


def test_the_motion_term_is_w3_times_the_squared_leg_steps(am, random_poses):
    (_, before), (_, after) = random_poses[1], random_poses[2]
    previous = _design_lengths(am.config, before)
    motion = MotionTerm(previous, max_step=0.5, w3=7.0)
    state = evaluate_state(am, after)
    steps = _design_lengths(am.config, after) - previous
    expected = _paper_omega(am.config, after, 1.0, 1.0) + 7.0 * np.sum(steps**2)
    assert objective_value(am, state, motion=motion) == pytest.approx(expected, rel=1e-9)
    assert motion_cost(state.leg_lengths, MotionTerm(previous, 0.5, 0.0)) == 0.0
    assert motion_cost(state.leg_lengths, None) == 0.0


def test_omega_is_written_in_objective_py_only():
    """No other module weighs the plate-deviation term itself: every caller goes through
    :mod:`assembler_pin.optimize.objective`."""
    root = Path(assembler_pin.__file__).parent
    pattern = re.compile(r"w2\s*\*\s*(np\.)?sqrt|sqrt\(\s*np\.sum\(\s*(lam|angles|v\.plate_angles)")
    writers = [
        str(path.relative_to(root))
        for path in sorted(root.rglob("*.py"))
        if path.name != "objective.py" and pattern.search(path.read_text(encoding="utf-8"))
    ]
    assert writers == []
