"""The clearance of the home pose on plain floats (no numpy, no Pinocchio).

The fast ``statics --home --json`` answer (:mod:`assembler_pin.statics.home`) carries the same
``clearance`` as :func:`~assembler_pin.collision.check.clearance` of the home pose: the smallest
leg–leg distance and leg–own-plate distance by the rule of :mod:`~assembler_pin.collision.pairs`
(the same pairs, in the same order, the same tie rule), once the other bodies measured through
coal in the full path (plates against legs and plates) are certainly farther: in the home pose
every plate is level, so a leg is at least ``home_height - thickness / 2 - motor_radius`` from
a plate it does not sit on and two plates are ``home_height - thickness`` apart or more; a payload of radius ``r`` is at
least ``offset - r - motor_radius`` from every leg and plate below it. A
leg's trimmed capsule against its own level plate is the height of the segment's end nearest
that plate above (below) the plate's face, minus the radius there, when that end lies over
the disc and the segment does not reach the face. When any of that does not hold,
:func:`home_clearance` returns None and the caller takes the full path.
"""

from __future__ import annotations

import math

from ..config.schema import AssemblerConfig

__all__ = ["TIE", "home_clearance", "segment_distance"]

#: Distances within this of the smallest are ties, broken by the pairs' order [m]: above
#: coal's noise (:data:`~assembler_pin.collision.screens.GJK_TOLERANCE`), so that equal pairs
#: measured by coal (the legs against their own level plates at home) name the first.
TIE = 1e-9

Vec = list[float]


def segment_distance(p1: Vec, d1: Vec, p2: Vec, d2: Vec) -> float:
    """Distance between the segments ``p1 + s d1`` and ``p2 + t d2`` (s, t in [0, 1]) [m]:
    the closed form of :func:`~assembler_pin.collision.distance.segment_segment` on floats."""
    r = [p1[k] - p2[k] for k in range(3)]
    a = sum(x * x for x in d1)
    e = sum(x * x for x in d2)
    b = sum(d1[k] * d2[k] for k in range(3))
    c = sum(d1[k] * r[k] for k in range(3))
    f = sum(d2[k] * r[k] for k in range(3))
    den = a * e - b * b
    s = (b * f - c * e) / den if den > 1e-12 * a * e else 0.0
    s = min(max(s, 0.0), 1.0)
    t = min(max((b * s + f) / max(e, 1e-300), 0.0), 1.0)
    s = min(max((b * t - c) / max(a, 1e-300), 0.0), 1.0)
    w = [r[k] + s * d1[k] - t * d2[k] for k in range(3)]
    return math.sqrt(sum(x * x for x in w))


def _nodes(n: int) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
    bottom = [(j, i // 2) for j in range(n) for i in range(6)]
    top = [(j + 1, i // 2 if i % 2 == 0 else (i // 2 - 1) % 3) for j in range(n) for i in range(6)]
    return bottom, top


def home_clearance(cfg: AssemblerConfig, bottom_in_plate: list, top_in_plate: list) -> dict | None:
    """``{"min_distance_m", "between"}`` of the home pose, or None (take the full path).

    Args:
        bottom_in_plate, top_in_plate: (n, 6, 3) joint centres in their plate's frame [m]
            (:func:`~assembler_pin.statics.home.home_anchors`).
    """
    n, h, leg = cfg.platforms, cfg.home_height, cfg.leg
    b = [[x, y, z + j * h] for j in range(n) for x, y, z in bottom_in_plate[j]]
    t = [[x, y, z + (j + 1) * h] for j in range(n) for x, y, z in top_in_plate[j]]
    length = [math.dist(b[g], t[g]) for g in range(6 * n)]
    axis = [[(t[g][k] - b[g][k]) / length[g] for k in range(3)] for g in range(6 * n)]
    nb, nt = _nodes(n)

    def segment(g: int, motor: bool, trim_bottom: bool, trim_top: bool) -> tuple[Vec, Vec, float, bool]:
        lo = max(0.0 if motor else leg.motor_length, leg.node_zone if trim_bottom else 0.0)
        hi = min(leg.motor_length if motor else length[g], length[g] - leg.node_zone if trim_top else math.inf)
        start = [b[g][k] + lo * axis[g][k] for k in range(3)]
        vec = [max(hi - lo, 0.0) * axis[g][k] for k in range(3)]
        return start, vec, leg.motor_radius if motor else leg.shaft_radius, hi >= lo

    distances: list[tuple[float, int, int]] = []
    for ga in range(6 * n):
        for gb in range(ga + 1, 6 * n):
            ta = (nb[ga] in (nb[gb], nt[gb]), nt[ga] in (nb[gb], nt[gb]))
            tb = (nb[gb] in (nb[ga], nt[ga]), nt[gb] in (nb[ga], nt[ga]))
            best = math.inf
            for ma, mb in ((True, True), (True, False), (False, True), (False, False)):
                sa, va, ra, oka = segment(ga, ma, *ta)
                sb, vb, rb, okb = segment(gb, mb, *tb)
                if oka and okb:
                    best = min(best, segment_distance(sa, va, sb, vb) - ra - rb)
            distances.append((best, ga, gb))
    own = _own_plates(cfg, b, length, axis)
    if not distances or own is None:
        return None
    rows = [(d, f"SP{ga // 6} leg {ga % 6}", f"SP{gb // 6} leg {gb % 6}") for d, ga, gb in distances]
    rows += [(d, f"SP{g // 6} leg {g % 6}", f"plate {g // 6 + end}") for d, g, end in own]
    dmin = min(d for d, _, _ in rows)
    plates_bound = min(h - 0.5 * cfg.plate.thickness - leg.motor_radius, h - cfg.plate.thickness)
    if cfg.payload.radius > 0:  # the payload, offset above plate n; every leg and plate below it
        plates_bound = min(plates_bound, cfg.payload.offset - cfg.payload.radius - leg.motor_radius)
    if not dmin < plates_bound - 1e-9:
        return None
    _, a, c = next(x for x in rows if x[0] <= dmin + TIE)
    return {"min_distance_m": dmin, "between": [a, c]}


def _own_plates(cfg: AssemblerConfig, b: list[Vec], length: list[float], axis: list[Vec]) -> list | None:
    """Each leg against its bottom plate, then its top plate, beyond ``node_zone`` from the
    joint there: ``(d, g, end)`` [m] in the full path's order; None when a leg is not rising
    or a part touches its plate (the full path measures the depth)."""
    leg, h = cfg.leg, cfg.home_height
    out = []
    for g in range(len(length)):
        j, L = g // 6, length[g]
        if axis[g][2] <= 0.0:
            return None
        for end in (0, 1):
            best = math.inf
            for lo, hi, radius in ((0.0, leg.motor_length, leg.motor_radius), (leg.motor_length, L, leg.shaft_radius)):
                lo = max(lo, leg.node_zone) if end == 0 else lo
                hi = min(hi, L - leg.node_zone) if end == 1 else hi
                if hi < lo:
                    continue
                d = _part_to_disc(cfg, b[g], axis[g], lo, hi, end, (j + end) * h)
                if d is None:
                    return None
                best = min(best, d - radius)
            out.append((best, g, end))
    return out


def _part_to_disc(cfg: AssemblerConfig, b: Vec, u: Vec, lo: float, hi: float, end: int, z: float) -> float | None:
    """Distance [m] of the axis segment ``b + σ u``, σ in [lo, hi], to the level plate at
    height ``z`` (a solid disc centred on the z axis) that the segment rises from (end 0) or
    to (end 1); None when they touch. The end nearest the plate when it lies over the disc
    (the face is the closest of the disc there); else the smallest point–disc distance along
    the segment, a convex function, by golden-section search."""
    radius, half = cfg.plate.radius, 0.5 * cfg.plate.thickness

    def to_disc(sigma: float) -> tuple[float, float, float]:
        x, y, zz = (b[k] + sigma * u[k] for k in range(3))
        return max(math.hypot(x, y) - radius, 0.0), max(abs(zz - z) - half, 0.0), math.hypot(x, y)

    near = lo if end == 0 else hi
    _, up, rho = to_disc(near)
    if up <= 0.0:
        return None
    if rho <= radius:
        return up
    a, c = lo, hi
    ratio = 0.5 * (math.sqrt(5.0) - 1.0)
    for _ in range(90):
        m1, m2 = c - ratio * (c - a), a + ratio * (c - a)
        if math.hypot(*to_disc(m1)[:2]) <= math.hypot(*to_disc(m2)[:2]):
            c = m2
        else:
            a = m1
    best = min(math.hypot(*to_disc(sigma)[:2]) for sigma in (lo, hi, 0.5 * (a + c)))
    return best if best > 0.0 else None
