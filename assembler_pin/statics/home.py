"""The state of the home pose without Pinocchio or numpy: ``assembler-pin statics --home --json``.

The home pose (:func:`~assembler_pin.model.geometry.home_plates`: plate 0 at the world origin,
every plate level, consecutive plates ``home_height`` apart, every leg at mid-stroke)
follows from the configuration alone, and so do its statics: the closed-form equilibrium of
:mod:`~assembler_pin.statics.loops`, interpreted on plain floats. This answers the
command in a fraction of the time that loading numpy and Pinocchio takes.

:func:`home_state_document` gives the same document as
``evaluate_state(am, am.home).to_dict()`` (the tests hold it key by key to the Pinocchio
path) when the home pose is strictly inside every limit; otherwise it returns None and the
caller takes the full path, which owns the list of violations.

Frames: world, z up; plate 0's frame is the world's. Lengths [m], forces [N] (tension
positive), angles in degrees where the key says so.
"""

from __future__ import annotations

import math

from ..config.schema import AssemblerConfig
from .loops import Grid, closed_form_pure, constants

__all__ = ["SCREEN_CONDITION", "home_anchors", "home_state_document"]

#: The largest condition number the fast path answers; a home pose less well conditioned
#: (far below :data:`~assembler_pin.statics.CONDITION_LIMIT`) takes the full path.
SCREEN_CONDITION = 1e6

#: Relative margin a value must keep from its limit for the fast path to call it inside.
_MARGIN = 1e-9

Vec = list[float]


def home_anchors(cfg: AssemblerConfig) -> tuple[list[list[Vec]], list[list[Vec]]]:
    """Bottom and top joint centres (n, 6, 3) in their plate's frame [m]: the rule of
    :func:`~assembler_pin.model.geometry.leg_geometry` (module docstring of
    :mod:`~assembler_pin.model.geometry`) on plain floats."""
    r, half, third = cfg.plate.node_radius, 0.5 * cfg.node_spacing, math.radians(60.0)

    def point(angle: float) -> Vec:
        return [r * math.cos(angle), r * math.sin(angle), 0.0]

    bottom, top = [], []
    for j in range(cfg.platforms):
        b_row, t_row = [], []
        for m in range(3):
            node = math.radians(90.0 + 60.0 * j + 120.0 * m)
            b_row += [point(node + half), point(node - half)]
            t_row += [point(node + third - half), point(node - third + half)]
        bottom.append(b_row)
        top.append(t_row)
    return bottom, top


def _unit(v: Vec) -> tuple[Vec, float]:
    length = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return [x / length for x in v], length


def _legs(cfg: AssemblerConfig, heights: Vec) -> dict:
    """World joint centres, lengths, deflections [rad] and rise [m] of every leg at home."""
    h = cfg.home_height
    bottom_in, top_in = home_anchors(cfg)
    out: dict = {"bottom": [], "top": [], "lengths": [], "deflection": [], "rise": []}
    for j in range(cfg.platforms):
        rows: dict[str, list] = {key: [] for key in out}
        for i in range(6):
            b, t = bottom_in[j][i], top_in[j][i]
            home_dir, _ = _unit([t[0] - b[0], t[1] - b[1], t[2] + h - b[2]])
            bw = [b[0], b[1], b[2] + heights[j]]
            tw = [t[0], t[1], t[2] + heights[j + 1]]
            u, length = _unit([tw[a] - bw[a] for a in range(3)])
            dot = u[0] * home_dir[0] + u[1] * home_dir[1] + u[2] * home_dir[2]
            angle = math.acos(min(1.0, max(-1.0, dot)))  # level plates: the same at both ends
            for key, value in zip(rows, (bw, tw, length, [angle, angle], u[2] * length), strict=True):
                rows[key].append(value)
        for key in out:
            out[key].append(rows[key])
    return out


def _statics(cfg: AssemblerConfig, heights: Vec) -> tuple[list[list[float]], list[float], list[float]]:
    """Forces (n, 6) [N], condition numbers (n,) and the base wrench [N, N·m] at home."""
    n = cfg.platforms
    eye = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    R = Grid((1, n + 1, 3, 3), eye * (n + 1))
    p = Grid((1, n + 1, 3), [x for z in heights for x in (0.0, 0.0, z)])
    bottom_in, top_in = home_anchors(cfg)
    bottom = Grid((n, 6, 3), [x for row in bottom_in for pt in row for x in pt])
    top = Grid((n, 6, 3), [x for row in top_in for pt in row for x in pt])
    forces, condition, _, base = closed_form_pure(R, p, bottom, top, constants(cfg))
    return forces.nested()[0], condition.data, base.data


def _inside(value: float, low: float, high: float) -> bool:
    """``low < value < high`` with a relative margin (False for NaN); ``high`` may be inf."""
    top = high - _MARGIN * max(1.0, abs(high)) if math.isfinite(high) else high
    return low + _MARGIN * max(1.0, abs(low)) < value < top


def _clearly_feasible(cfg: AssemblerConfig, legs: dict, forces: list, condition: list) -> bool:
    """Every constraint of :func:`~assembler_pin.constraints.evaluate_constraints` (no goal)
    holds with a margin: lengths, deflections, rise, forces, conditioning."""
    leg = cfg.leg
    cos_limit = math.cos(leg.max_deflection)
    for j in range(cfg.platforms):
        if not condition[j] <= SCREEN_CONDITION:
            return False
        for i in range(6):
            checks = (
                _inside(legs["lengths"][j][i], leg.min_length, leg.max_length),
                _inside(math.cos(legs["deflection"][j][i][0]), cos_limit, math.inf),
                _inside(legs["rise"][j][i], 0.0, math.inf),
                _inside(forces[j][i], -leg.max_compression, leg.max_tension),
            )
            if not all(checks):
                return False
    return True


def home_state_document(cfg: AssemblerConfig, clearance: dict | None) -> dict | None:
    """The document of ``evaluate_state(am, am.home).to_dict()`` for the model of ``cfg``, or
    None when the home pose is not strictly inside every limit (take the full path then).

    Args:
        clearance: the home pose's clearance document
            (:func:`~assembler_pin.collision.home.home_clearance` of :func:`home_anchors`), or
            None when it could not be decided on plain floats.

    Keys: plates (n+1 4×4), leg_lengths (n, 6) [m], forces (n, 6) [N], bottom_points,
    top_points (n, 6, 3) world [m], max_abs_force, mean_abs_force [N], feasible, violations
    (empty), deflection_deg (n, 6, 2), base_wrench (6,) [N, N·m], condition (n,), clearance
    (:func:`~assembler_pin.collision.home.home_clearance`).
    """
    n = cfg.platforms
    heights = [0.0]
    for _ in range(n):  # as home_plates composes the plates: each one step above the last
        heights.append(heights[-1] + cfg.home_height)
    legs = _legs(cfg, heights)
    forces, condition, base = _statics(cfg, heights)
    if not _clearly_feasible(cfg, legs, forces, condition):
        return None
    near = clearance
    if near is None or not near["min_distance_m"] > cfg.clearance * (1.0 + _MARGIN):
        return None
    plates = [[[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]] for z in heights]
    magnitudes = [abs(f) for row in forces for f in row]
    return {
        "plates": plates,
        "leg_lengths": legs["lengths"],
        "forces": forces,
        "bottom_points": legs["bottom"],
        "top_points": legs["top"],
        "max_abs_force": max(magnitudes),
        "mean_abs_force": math.fsum(magnitudes) / len(magnitudes),
        "feasible": True,
        "violations": [],
        "deflection_deg": [[[math.degrees(a) for a in ends] for ends in row] for row in legs["deflection"]],
        "base_wrench": base,
        "condition": condition,
        "clearance": near,
    }
