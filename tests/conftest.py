"""Shared fixtures, independent reference computations and the test tiers.

Tiers (markers registered in pyproject.toml): every test runs by default; ``-m "not slow"``
is the fast tier. :func:`pytest_collection_modifyitems` marks by module and by the measured
list ``tests/slow_tests.txt`` (tests named by file name and test name, so a file moved to
another folder stays in its tier), so no test file carries tier decorators of its own.
"""

from __future__ import annotations

from pathlib import Path

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


# ---------------------------------------------------------------------- tiers
SLOW_LIST = Path(__file__).with_name("slow_tests.txt")


def read_slow_list(path: Path = SLOW_LIST) -> set[str]:
    """The tests of the slow tier, ``test_x.py::name`` or ``test_x.py::name[params]`` (the file
    name without its folder: file names are unique across tests/)."""
    ids = set()
    for line in path.read_text(encoding="utf-8").splitlines():
        entry = line.split("  #", 1)[0].strip()
        if entry and not entry.startswith("#"):
            ids.add(entry)
    return ids


def tier_markers(item: pytest.Item, slow_ids: set[str]) -> list[str]:
    """The tier markers of one collected test: by module, by name, and by the slow list."""
    path = Path(str(item.path))
    key = f"{path.name}::{item.nodeid.split('::', 1)[1]}" if "::" in item.nodeid else path.name
    marks = []
    if path.suffix == ".ipynb":
        marks += ["notebook", "slow"]
    if path.name == "test_mujoco.py":
        marks.append("mujoco")
    if path.name == "test_maps.py" and "dask" in item.name:
        marks.append("dask")
    if "browser" in item.name:
        marks.append("browser")
    if key in slow_ids or key.split("[", 1)[0] in slow_ids:
        marks.append("slow")
    return list(dict.fromkeys(marks))


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark every collected item with its tiers (before ``-m`` selects among them)."""
    slow_ids = read_slow_list()
    for item in items:
        for name in tier_markers(item, slow_ids):
            item.add_marker(getattr(pytest.mark, name))
