"""Shared fixtures and independent reference computations for the tests."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from checks import design_anchors

from assembler_pin import AssemblerModel, load_config, stack_forward_kinematics


@pytest.fixture(scope="session")
def am() -> AssemblerModel:
    """The default 4-platform model."""
    return AssemblerModel.from_config()


@pytest.fixture(scope="session")
def random_poses(am):
    """Eight random reachable poses: (lengths (n, 6), plates), built by stack FK."""
    rng = np.random.default_rng(42)
    out = []
    leg = am.config.leg
    while len(out) < 8:
        lengths = rng.uniform(leg.min_length + 0.02, leg.max_length - 0.02, (am.n, 6))
        fk = stack_forward_kinematics(am, lengths)
        if fk.success:
            out.append((lengths, fk.plates))
    return out


def potential_energy(cfg, plates) -> float:
    """Gravitational potential energy [J] of the stack, computed from geometry alone.

    Independent of Pinocchio: bodies are placed from the plate poses and the anchor
    geometry written out again here (node angles of the design notes).
    """
    n = cfg.platforms
    g = cfg.gravity
    energy = 0.0
    for k in range(n + 1):
        energy += cfg.plate.mass * g * plates.p[k][2]
    for j in range(n):
        bottom, top = design_anchors(cfg, j)
        for b_local, t_local in zip(bottom, top, strict=True):
            b = plates.R[j] @ b_local + plates.p[j]
            t = plates.R[j + 1] @ t_local + plates.p[j + 1]
            u = (t - b) / np.linalg.norm(t - b)
            energy += cfg.leg.motor_mass * g * (b + cfg.leg.motor_com * u)[2]
            energy += cfg.leg.shaft_mass * g * (t - cfg.leg.shaft_com * u)[2]
    payload = plates.R[n] @ [0, 0, cfg.payload.offset] + plates.p[n]
    energy += cfg.payload.mass * g * payload[2]
    return float(energy)


def random_se3(rng: np.random.Generator, scale: float = 1.0) -> pin.SE3:
    return pin.exp6(rng.normal(size=6) * scale)


@pytest.fixture(scope="session")
def massless_am() -> AssemblerModel:
    cfg = load_config({"leg": {"motor_mass": 0.0, "shaft_mass": 0.0}})
    return AssemblerModel.from_config(cfg)


@pytest.fixture(scope="session")
def bent_plates(am):
    """A reachable bent pose (stack FK of uneven leg lengths), for drawing tests."""
    lengths = np.full((am.n, 6), 0.275)
    lengths[0, :3] = 0.22
    lengths[1, 3:] = 0.33
    return stack_forward_kinematics(am, lengths).raise_if_failed()
