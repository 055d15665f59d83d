"""What one platform can do: the helper arm's joint limits and the heights of a level platform.

A cluster of the helper arm tilts and twists one Stewart platform about its mid-height
point. :func:`cluster_limits` finds the largest such tilt and twist that keep every leg
within its limits (:func:`~assembler_pin.constraints.leg_limit_margins`), and
:func:`height_range` the heights a level platform can have. Angles in radians, lengths in
metres.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..config.schema import AssemblerConfig
from ..constraints import leg_limit_margins
from ..kinematics.legs import relative_leg_measures
from ..model.geometry import LegGeometry, leg_geometry

__all__ = ["cached_leg_geometry", "cluster_limits", "height_range"]

_AXIS_COUNT = 24  # horizontal tilt axes tried by cluster_limits (every 15 degrees)
_BISECTION_TOL = 1e-10  # [rad] and [m]


# ---------------------------------------------------------------------- SP validity
@functools.lru_cache(maxsize=64)
def cached_leg_geometry(cfg: AssemblerConfig) -> LegGeometry:
    """:func:`~assembler_pin.model.geometry.leg_geometry`, cached per configuration (immutable)."""
    return leg_geometry(cfg)


def _rotations(rotvecs: np.ndarray) -> np.ndarray:
    """exp3 of each row of (m, 3) rotation vectors → (m, 3, 3) (Rodrigues, vectorized)."""
    theta = np.linalg.norm(rotvecs, axis=1)
    safe = np.where(theta > 0.0, theta, 1.0)
    k = rotvecs / safe[:, None]
    kx = np.zeros((rotvecs.shape[0], 3, 3))
    kx[:, 0, 1], kx[:, 0, 2], kx[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    kx -= kx.transpose(0, 2, 1)
    s, c = np.sin(theta)[:, None, None], (1.0 - np.cos(theta))[:, None, None]
    return np.eye(3) + s * kx + c * (kx @ kx)


def _sp_valid(cfg: AssemblerConfig, rotations: np.ndarray, translations: np.ndarray) -> np.ndarray:
    """Whether each relative pose (top plate in the bottom plate's frame) is a valid pose of
    every platform of the stack (:func:`~assembler_pin.constraints.leg_limit_margins`).

    Args:
        rotations: (m, 3, 3); translations: (m, 3) [m].

    Returns:
        (m,) booleans.
    """
    lengths, cos, rise = relative_leg_measures(cached_leg_geometry(cfg), rotations[:, None], translations[:, None])
    m = leg_limit_margins(cfg.leg, lengths, cos, rise)
    ok = (m[:4] >= 0).all(axis=0) & (m[4] > 0)
    return ok.reshape(ok.shape[0], -1).all(axis=1)


def _about_mid_height(rotations: np.ndarray, d: float) -> tuple[np.ndarray, np.ndarray]:
    """Relative poses ``T(d/2)·R·T(d/2)`` of an SP tilted about its mid-height point."""
    half = np.array([0.0, 0.0, 0.5 * d])
    return rotations, half + rotations @ half


def _bisect_angles(cfg: AssemblerConfig, axes: np.ndarray, d: float, upper: float = 0.5 * math.pi) -> np.ndarray:
    """Largest angle θ in [0, upper] along each unit axis (m, 3) such that the SP rotated by
    ``exp3(θ·axis)`` about its mid-height point at height d stays valid (bisection, all axes
    at once). Returns 0 where the level SP itself is invalid."""
    m = axes.shape[0]
    lo = np.zeros(m)
    hi = np.full(m, upper)

    def valid(angles: np.ndarray) -> np.ndarray:
        rots = _rotations(angles[:, None] * axes)
        return _sp_valid(cfg, *_about_mid_height(rots, d))

    if not valid(lo).all():
        return np.zeros(m)
    top_ok = valid(hi)
    while (hi - lo).max() > _BISECTION_TOL:
        mid = 0.5 * (lo + hi)
        ok = valid(mid)
        lo = np.where(ok, mid, lo)
        hi = np.where(ok, hi, mid)
    return np.where(top_ok, upper, lo)


@functools.lru_cache(maxsize=256)
def cluster_limits(cfg: AssemblerConfig, link_length: float) -> tuple[float, float]:
    """Joint limits of one helper-arm cluster at link length ``d`` [rad].

    Derived numerically from the leg stroke and deflection limit: the tilt limit is the
    smallest, over 24 horizontal axes (every 15°), of the largest tilt of an SP about its
    mid-height point (relative pose ``T(d/2)·exp3(θ·a)·T(d/2)``) that keeps every leg of
    every platform within ``[min_length, max_length]``, both deflections within
    ``max_deflection`` and the top joints above the bottom ones (bisection to 1e-10 rad).
    The twist limit is the same for a rotation about z, smallest of both signs.

    Returns:
        (tilt limit for the x and y joints, twist limit for the z joint) [rad]; the joint
        ranges are ``[-limit, +limit]``. Both are 0 when a level SP cannot have height d.
    """
    phi = np.deg2rad(np.arange(_AXIS_COUNT) * (360.0 / _AXIS_COUNT))
    tilt_axes = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
    twist_axes = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    tilt = float(_bisect_angles(cfg, tilt_axes, link_length).min())
    twist = float(_bisect_angles(cfg, twist_axes, link_length).min())
    return tilt, twist


@functools.lru_cache(maxsize=32)
def height_range(cfg: AssemblerConfig) -> tuple[float, float]:
    """Heights ``[d_min, d_max]`` a level SP (plates parallel, no twist) can have [m].

    Found by bisection on each side of the home height with the same validity test as
    :func:`cluster_limits`; the helper arm's link length is kept within this range.
    """
    d0 = cfg.home_height

    def valid(d: float) -> bool:
        return bool(_sp_valid(cfg, np.eye(3)[None], np.array([[0.0, 0.0, d]]))[0])

    def edge(inside: float, outside: float) -> float:
        while abs(outside - inside) > _BISECTION_TOL:
            mid = 0.5 * (inside + outside)
            inside, outside = (mid, outside) if valid(mid) else (inside, mid)
        return inside

    return edge(d0, 0.0), edge(d0, 2.0 * cfg.leg.max_length)
