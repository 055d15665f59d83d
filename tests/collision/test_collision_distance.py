"""The closed-form distances against the tests' own minimizer, dense sampling and coal."""

from __future__ import annotations

import coal
import numpy as np
import pytest
from checks import brute_segment_distance

from assembler_pin.collision.distance import (
    cylinder_lowest_point,
    point_in_cylinder_distance,
    segment_point,
    segment_segment,
)

RNG = np.random.default_rng(42)


def _segment_cases(count: int) -> list[tuple[np.ndarray, ...]]:
    cases = []
    for _ in range(count):
        p1, d1, p2, d2 = RNG.normal(size=(4, 3)) * 0.3
        cases.append((p1, d1, p2, d2))
    p = RNG.normal(size=3)
    d = RNG.normal(size=3)
    up, side, both = np.array([0.0, 0.0, 0.1]), np.array([0.1, 0.0, 0.0]), np.array([0.1, 0.2, 0.0])
    cases += [
        (p, d, p + up, d),  # parallel, overlapping
        (p, d, p + 2 * d + 0.5 * both - side, d),  # parallel, apart along the axis
        (p, np.zeros(3), p + side, d),  # a point and a segment
        (p, np.zeros(3), p + both, np.zeros(3)),  # two points
        (p, d, p + 0.3 * d + side, np.zeros(3)),  # a segment and a point
        (p, d, p - up, 1e-9 * d),  # a segment and a nearly zero-length one
        (p, d, p + 0.5 * d, np.cross(d, [0.0, 0.0, 1.0])),  # crossing
    ]
    return cases


def test_segment_segment_against_a_minimizer():
    cases = _segment_cases(200)
    p1, d1, p2, d2 = (np.array(x) for x in zip(*cases, strict=True))
    dist, s, t = segment_segment(p1, d1, p2, d2)
    for k, case in enumerate(cases):
        assert dist[k] == pytest.approx(brute_segment_distance(*case), abs=1e-7), k
    witness = p1 + s[:, None] * d1 - p2 - t[:, None] * d2
    np.testing.assert_allclose(np.linalg.norm(witness, axis=1), dist, atol=1e-12)
    assert ((s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)).all()


def test_segment_segment_against_coal_capsules():
    """coal's capsule distance minus nothing: capsules of radius r1, r2 give d - r1 - r2."""
    req = coal.DistanceRequest()
    for p1, d1, p2, d2 in _segment_cases(50)[:50]:
        if np.linalg.norm(d1) < 1e-9 or np.linalg.norm(d2) < 1e-9:
            continue
        shapes = []
        for p, d in ((p1, d1), (p2, d2)):
            u = d / np.linalg.norm(d)
            a = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
            x = np.cross(a, u)
            x /= np.linalg.norm(x)
            R = np.column_stack([x, np.cross(u, x), u])
            shapes.append((coal.Capsule(0.01, float(np.linalg.norm(d))), coal.Transform3s(R, p + 0.5 * d)))
        res = coal.DistanceResult()
        got = coal.distance(shapes[0][0], shapes[0][1], shapes[1][0], shapes[1][1], req, res)
        want = segment_segment(p1, d1, p2, d2)[0] - 0.02
        if want > 1e-3:  # coal's GJK is exact for separated capsules
            assert got == pytest.approx(want, abs=1e-6)


def test_segment_point_against_sampling():
    p, d, c = RNG.normal(size=(3, 100, 3))
    dist, _ = segment_point(p, d, c)
    grid = np.linspace(0.0, 1.0, 20001)
    for k in range(100):
        sampled = np.linalg.norm(p[k] + grid[:, None] * d[k] - c[k], axis=1).min()
        assert dist[k] <= sampled + 1e-12
        assert dist[k] == pytest.approx(sampled, abs=1e-7)


def _random_rotation() -> np.ndarray:
    q, _ = np.linalg.qr(RNG.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def test_cylinder_lowest_point_against_its_rim():
    radius, thickness = 0.17, 0.01
    angles = np.linspace(0.0, 2 * np.pi, 20001)
    for _ in range(30):
        R, c = _random_rotation(), RNG.normal(size=3)
        point, height = cylinder_lowest_point(c[None], R[None, :, 2], radius, thickness)
        rim = radius * (np.cos(angles)[:, None] * R[:, 0] + np.sin(angles)[:, None] * R[:, 1])
        lowest = min((c + rim + side * 0.5 * thickness * R[:, 2])[:, 2].min() for side in (-1, 1))
        assert height[0] == pytest.approx(lowest, abs=1e-7)
        local = R.T @ (point[0] - c)
        assert np.hypot(local[0], local[1]) == pytest.approx(radius) and abs(local[2]) == pytest.approx(0.5 * thickness)


def test_point_in_cylinder_distance_against_coal():
    radius, thickness = 0.17, 0.04
    cyl, sphere = coal.Cylinder(radius, thickness), coal.Sphere(1e-9)
    req = coal.DistanceRequest()
    for local in RNG.normal(size=(200, 3)) * [0.2, 0.2, 0.05]:
        d, closest = point_in_cylinder_distance(local, radius, thickness)
        res = coal.DistanceResult()
        want = coal.distance(cyl, coal.Transform3s(), sphere, coal.Transform3s(np.eye(3), local), req, res)
        if d > 1e-6:
            assert float(d) == pytest.approx(want, abs=1e-6)
            assert np.linalg.norm(local - closest) == pytest.approx(float(d), abs=1e-9)
        else:  # inside: minus the depth to the nearest face or the rim
            depth = min(radius - np.hypot(local[0], local[1]), 0.5 * thickness - abs(local[2]))
            assert float(d) == pytest.approx(-depth, abs=1e-12)
