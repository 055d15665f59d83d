"""The numpy version of the compiled clearance kernel: the tests' independent reference.

:func:`reference_own_pairs` computes what
:func:`~assembler_pin.collision.kernel.own_pairs` computes (the legs' joint centres, every leg
pair's closest capsules and the screens' lower bounds), vectorized over pairs in numpy with
the tested closed form :func:`~assembler_pin.collision.distance.segment_segment_columns`
instead of the kernel's loops; the tests hold the two to 1e-12 m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from assembler_pin.collision import kernel
from assembler_pin.collision.distance import segment_point, segment_segment_columns
from assembler_pin.collision.kernel import OwnPairs
from assembler_pin.collision.kernel import kernel_inputs as compiled_inputs
from assembler_pin.collision.pairs import pair_table
from assembler_pin.config.schema import AssemblerConfig
from assembler_pin.model.geometry import LEGS_PER_PLATFORM


def _unit(v: np.ndarray) -> np.ndarray:
    norm = np.sqrt(np.einsum("...k,...k->...", v, v))
    fallback = np.broadcast_to(np.array([0.0, 0.0, 1.0]), v.shape)
    return np.where(norm[..., None] > 1e-15, v / np.maximum(norm, 1e-300)[..., None], fallback)


@dataclass(frozen=True)
class Variants:
    """The leg-part variants the pairs use (part × trims): leg, ``lo``, the two candidates of
    ``hi = min(a1 + b1 L, a2 + b2 L)``, radius; the pairs as rows into them."""

    g: np.ndarray
    lo: np.ndarray
    a1: np.ndarray
    b1: np.ndarray
    a2: np.ndarray
    b2: np.ndarray
    ia: np.ndarray
    ib: np.ndarray
    radius: np.ndarray


def variants(cfg: AssemblerConfig) -> Variants:
    """The variants of the configuration's leg pairs, decoded from the kernel's codes."""
    inp = compiled_inputs(cfg)
    used, inverse = np.unique(np.concatenate([inp.va, inp.vb]), return_inverse=True)
    g, shaft, tb, tt = used // 8, (used // 4) % 2 == 1, (used // 2) % 2 == 1, used % 2 == 1
    leg = cfg.leg
    lo = np.where(shaft, leg.motor_length, 0.0)
    lo = np.where(tb, np.maximum(lo, leg.node_zone), lo)
    a1, b1 = np.where(shaft, 0.0, leg.motor_length), shaft.astype(float)
    a2, b2 = np.where(tt, -leg.node_zone, np.inf), tt.astype(float)
    radius = np.where(shaft, leg.shaft_radius, leg.motor_radius)
    ia, ib = inverse[: len(inp.va)], inverse[len(inp.va) :]
    return Variants(g, lo, a1, b1, a2, b2, ia, ib, radius)


def _leg_pairs(v: Variants, bottom, axis, length) -> tuple[np.ndarray, np.ndarray]:
    """Every leg pair's distance (P,) [m] and row (P, kernel.ROW_WIDTH)."""
    Lg = length[v.g]
    h1, h2 = v.a1 + v.b1 * Lg, v.a2 + v.b2 * Lg
    hi = np.minimum(h1, h2)
    hb = np.where(h2 < h1, 1.0, v.b1)
    span = hi - v.lo
    axis_g = axis[v.g].T
    start = bottom[v.g].T + v.lo * axis_g  # (3, V)
    seg = np.maximum(span, 0.0) * axis_g
    axis_d, s, u = segment_segment_columns(start[:, v.ia], seg[:, v.ia], start[:, v.ib], seg[:, v.ib])
    d = axis_d - v.radius[v.ia] - v.radius[v.ib]
    empty = span < 0
    d[empty[v.ia] | empty[v.ib]] = np.inf
    P = len(d) // 4
    best = np.argmin(d.reshape(P, 4), axis=1) + 4 * np.arange(P)
    va, vb, sb, ub = v.ia[best], v.ib[best], s[best], u[best]
    full = np.maximum(span, 0.0)
    xa, xb = start[:, va] + sb * seg[:, va], start[:, vb] + ub * seg[:, vb]
    legs = np.empty((P, kernel.ROW_WIDTH))
    legs[:, kernel.ROW_XA : kernel.ROW_XA + 3], legs[:, kernel.ROW_XB : kernel.ROW_XB + 3] = xa.T, xb.T
    legs[:, kernel.ROW_NORMAL : kernel.ROW_NORMAL + 3] = _unit((xa - xb).T)
    legs[:, kernel.ROW_SIGMA], legs[:, kernel.ROW_SIGMA + 1] = v.lo[va] + sb * full[va], v.lo[vb] + ub * full[vb]
    legs[:, kernel.ROW_HB], legs[:, kernel.ROW_HB + 1] = sb * hb[va], ub * hb[vb]
    legs[:, kernel.ROW_RADIUS], legs[:, kernel.ROW_RADIUS + 1] = v.radius[va], v.radius[vb]
    return d[best], legs


def _leg_plate_bounds(cfg, leg_plate, trims, bottom, axis, length, R, p) -> np.ndarray:
    """A leg part (trimmed by ``node_zone`` at the ends ``trims`` (Q, 2) names) against a
    plate: its bounding sphere, and the slab of its faces (Q, 2) [m]."""
    leg = cfg.leg
    half, rho = 0.5 * cfg.plate.thickness, math.hypot(cfg.plate.radius, 0.5 * cfg.plate.thickness)
    lp_g, lp_k = np.repeat(leg_plate[:, 0], 2), np.repeat(leg_plate[:, 1], 2)
    shaft = np.tile(np.array([False, True]), len(leg_plate))
    L = length[lp_g]
    lo = np.where(shaft, leg.motor_length, 0.0)
    hi = np.where(shaft, L, leg.motor_length)
    lo = np.where(np.repeat(trims[:, 0], 2), np.maximum(lo, leg.node_zone), lo)
    hi = np.where(np.repeat(trims[:, 1], 2), np.minimum(hi, L - leg.node_zone), hi)
    r = np.where(shaft, leg.shaft_radius, leg.motor_radius)
    a0 = bottom[lp_g] + lo[:, None] * axis[lp_g] - p[lp_k]
    dk = (hi - lo)[:, None] * axis[lp_g]
    normal = R[lp_k][:, :, 2]
    d_centre, _ = segment_point(a0, dk, np.zeros(3))
    h0 = np.einsum("ij,ij->i", a0, normal)
    h1 = h0 + np.einsum("ij,ij->i", dk, normal)
    slab = np.maximum(np.minimum(h0, h1), -np.maximum(h0, h1)) - half - r
    lp = np.maximum(d_centre - rho - r, slab)
    # where the part is clear of the slab and its end nearer the plate lies over the disc, the
    # face below that end is the nearest of the plate: the distance is its height less the radius
    near_hi = np.abs(h1) < np.abs(h0)
    hn = np.where(near_hi, h1, h0)
    xn = a0 + np.where(near_hi, 1.0, 0.0)[:, None] * dk
    over = np.einsum("ij,ij->i", xn, xn) - hn * hn <= cfg.plate.radius**2
    clear = (np.minimum(h0, h1) > half) | (np.maximum(h0, h1) < -half)
    end = np.where(clear & over, near_hi.astype(float), -1.0)
    lp = np.where(end >= 0, np.abs(hn) - half - r, lp)
    lp[hi < lo], end[hi < lo] = np.inf, -1.0
    return lp.reshape(-1, 2), end.reshape(-1, 2)


def _plate_pair_bounds(cfg, plate_pairs, R, p) -> np.ndarray:
    """Plate against plate: bounding spheres, and each one's slab against the other's spread."""
    half, rho = 0.5 * cfg.plate.thickness, math.hypot(cfg.plate.radius, 0.5 * cfg.plate.thickness)
    ka, kb = plate_pairs[:, 0], plate_pairs[:, 1]
    dc = p[kb] - p[ka]
    pp = np.sqrt(np.einsum("ij,ij->i", dc, dc)) - 2.0 * rho
    na, nb = R[ka][:, :, 2], R[kb][:, :, 2]
    c = np.einsum("ij,ij->i", na, nb)
    spread = cfg.plate.radius * np.sqrt(np.maximum(1.0 - c * c, 0.0)) + half * np.abs(c) + half
    h = np.maximum(np.abs(np.einsum("ij,ij->i", na, dc)), np.abs(np.einsum("ij,ij->i", nb, dc)))
    return np.maximum(pp, h - spread)


def reference_own_pairs(
    cfg: AssemblerConfig, R: np.ndarray, p: np.ndarray, dist: np.ndarray, at: int, exact: np.ndarray
) -> OwnPairs:
    """:func:`~assembler_pin.collision.kernel.own_pairs` in numpy: the same arrays, the same
    entries of ``dist``."""
    inp = compiled_inputs(cfg)
    plate_of = np.arange(len(inp.bottom_in)) // LEGS_PER_PLATFORM
    bottom = np.einsum("gij,gj->gi", R[plate_of], inp.bottom_in) + p[plate_of]
    top = np.einsum("gij,gj->gi", R[plate_of + 1], inp.top_in) + p[plate_of + 1]
    vec = top - bottom
    length = np.sqrt(np.einsum("ij,ij->i", vec, vec))
    axis = vec / np.maximum(length, 1e-300)[:, None]
    d, legs = _leg_pairs(variants(cfg), bottom, axis, length)
    dist[: len(d)] = d
    t = pair_table(cfg)
    lp, end = _leg_plate_bounds(cfg, t.leg_plate, t.leg_plate_trim, bottom, axis, length, R, p)
    pp = _plate_pair_bounds(cfg, t.plate_pairs, R, p)
    Q = len(lp)
    near = (lp[:, 1] < lp[:, 0]).astype(np.int64)
    row = np.stack([near, end[np.arange(Q), near].astype(np.int64)], axis=1)
    exact[at : at + Q] |= row[:, 1] >= 0
    dist[at : at + Q] = lp.min(axis=1)
    dist[at + Q : at + Q + len(pp)] = pp
    return OwnPairs(np.stack([bottom, top, axis]), length, legs, lp, end, row)
