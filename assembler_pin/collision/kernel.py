"""The compiled loop of the stack's own pairs: the leg–leg closed form and the screens.

:func:`_self_py` is the self-collision pass of :mod:`~assembler_pin.collision.check` written
as plain loops over legs and pairs: the joint centres of every leg from the plate poses, the
smallest of the four capsule pairs (motor/shaft × motor/shaft, trimmed by the pair rule) of
every leg pair with its closest points, and the lower bounds of the leg–plate and plate–plate
pairs that coal measures when near. numba compiles it (``cache=True``: once per install and
Python version, a few seconds the first time) on the first clearance of a process; a new
process then loads the cached kernel when it first measures a clearance, not at import, so
that commands that measure none start as fast as before. It is the one engine of the
clearance; the tests hold it to an independent numpy version to 1e-12 m.

Frames: world, z up; lengths [m].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..config.schema import AssemblerConfig
from ..model.geometry import leg_geometry
from .pairs import pair_table, per_config

__all__ = [
    "ROW_RADIUS",
    "ROW_WIDTH",
    "SIZE_NAMES",
    "KernelInputs",
    "OwnPairs",
    "kernel_inputs",
    "own_pairs",
    "variant_index",
]

#: The entries of the kernel's ``sizes`` array.
SIZE_NAMES = ("motor_length", "node_zone", "motor_radius", "shaft_radius", "plate_radius", "half_thickness", "rho")

_kernel: Any = None  # the compiled function (None: not yet)


def _variant_py(code, L, sizes):  # pragma: no cover - compiled
    """(leg, lo, hi, hb, radius) of a leg-part variant ``code = 8 g + 4 part + 2 trim_bottom +
    trim_top`` (:func:`~assembler_pin.collision.bodies.leg_segments`)."""
    g = code // 8
    part = (code // 4) % 2
    tb = (code // 2) % 2
    tt = code % 2
    motor_length, zone = sizes[0], sizes[1]
    lo = motor_length if part == 1 else 0.0
    if tb == 1 and zone > lo:
        lo = zone
    hi = L[g] if part == 1 else motor_length
    hb = 1.0 if part == 1 else 0.0
    if tt == 1 and L[g] - zone < hi:
        hi = L[g] - zone
        hb = 1.0
    radius = sizes[3] if part == 1 else sizes[2]
    return g, lo, hi, hb, radius


_variant = _variant_py  # interpreted here; the compiled kernel calls a compiled copy

#: Columns of the kernel's leg-pair rows: the closest points on the two axes (x_a, x_b),
#: the unit normal from leg b to leg a, σ of the two points [m], dσ/dL of the two points,
#: the radii of the two capsules (motor or shaft) that hold them [m].
ROW_XA, ROW_XB, ROW_NORMAL, ROW_SIGMA, ROW_HB, ROW_RADIUS, ROW_WIDTH = 0, 3, 6, 9, 11, 13, 15


def _self_py(
    R,
    p,
    bottom_in,
    top_in,
    va,
    vb,
    leg_plate,
    plate_pairs,
    sizes,
    base,
    BTU,
    L,
    dist,
    rows,
    lp_lb,
    lp_end,
    lp_row,
    exact,
):  # pragma: no cover - compiled
    """Fills the legs' joint centres ``BTU[0]``, ``BTU[1]`` (G, 3), directions ``BTU[2]`` (G, 3)
    and lengths L (G,) [m]; per leg pair q the distance ``dist[q]`` [m] and its row ``rows[q]``
    (:data:`ROW_XA`...: closest points on the axes, world [m], normal from leg b to leg a, σ
    [m], dσ/dL); the lower bounds lp_lb (Q, 2) of each leg part (trimmed as ``leg_plate``'s
    last two columns say) against each plate, their
    smaller one in ``dist[base + q]``, and of each plate pair in ``dist[base + Q + q]`` [m].

    Each capsule pair is the closed form of
    :func:`~assembler_pin.collision.distance.segment_segment` written on the two axes'
    parameters: per leg pair, the scalars ``u_a · u_b``, ``u_a · Δ`` and ``u_b · Δ`` (``Δ`` the
    offset of the bottom joints) give its dot products, and ``1 / |d|²`` comes once per leg
    part; the distance is taken from the 3-vector between the two closest points."""
    G = bottom_in.shape[0]
    B, T, U = BTU[0], BTU[1], BTU[2]
    for g in range(G):
        j = g // 6
        ln = 0.0
        for k in range(3):
            B[g, k] = (
                p[j, k] + R[j, k, 0] * bottom_in[g, 0] + R[j, k, 1] * bottom_in[g, 1] + R[j, k, 2] * bottom_in[g, 2]
            )
            T[g, k] = (
                p[j + 1, k]
                + R[j + 1, k, 0] * top_in[g, 0]
                + R[j + 1, k, 1] * top_in[g, 1]
                + R[j + 1, k, 2] * top_in[g, 2]
            )
            ln += (T[g, k] - B[g, k]) ** 2
        L[g] = math.sqrt(ln)
        for k in range(3):
            U[g, k] = (T[g, k] - B[g, k]) / max(L[g], 1e-300)
    V = 8 * G  # every leg part with and without each trim: its span, once
    vlo, vhi, vhb, vr = np.empty(V), np.empty(V), np.empty(V), np.empty(V)
    vlen, vsq, vinv = np.empty(V), np.empty(V), np.empty(V)
    for code in range(V):
        g, lo, hi, hbc, radius = _variant(code, L, sizes)
        vlo[code], vhi[code], vhb[code], vr[code] = lo, hi, hbc, radius
        span = hi - lo if hi >= lo else 0.0
        vlen[code], vsq[code] = span, span * span
        vinv[code] = 1.0 / max(span * span, 1e-300)
    for q in range(rows.shape[0]):
        ga, gb = va[4 * q] // 8, vb[4 * q] // 8
        D0, D1, D2 = B[ga, 0] - B[gb, 0], B[ga, 1] - B[gb, 1], B[ga, 2] - B[gb, 2]
        ua0, ua1, ua2 = U[ga, 0], U[ga, 1], U[ga, 2]
        ub0, ub1, ub2 = U[gb, 0], U[gb, 1], U[gb, 2]
        uab = ua0 * ub0 + ua1 * ub1 + ua2 * ub2
        wa = ua0 * D0 + ua1 * D1 + ua2 * D2
        wb = ub0 * D0 + ub1 * D1 + ub2 * D2
        br = 4 * q
        best, bs, bt = math.inf, 0.0, 0.0
        bsa, bsb = vlo[va[br]], vlo[vb[br]]
        for r in range(4 * q, 4 * q + 4):
            ca, cb = va[r], vb[r]
            if vhi[ca] < vlo[ca] or vhi[cb] < vlo[cb]:
                continue
            la, lb = vlo[ca], vlo[cb]
            na, nb = vlen[ca], vlen[cb]
            a, e = vsq[ca], vsq[cb]
            b = na * nb * uab
            c = na * (wa + la - lb * uab)
            f = nb * (wb + la * uab - lb)
            den = a * e - b * b
            s = (b * f - c * e) / den if den > 1e-12 * a * e else 0.0
            s = min(max(s, 0.0), 1.0)
            t = min(max((b * s + f) * vinv[cb], 0.0), 1.0)
            s = min(max((b * t - c) * vinv[ca], 0.0), 1.0)
            sa, sb = la + s * na, lb + t * nb
            w0 = D0 + sa * ua0 - sb * ub0
            w1 = D1 + sa * ua1 - sb * ub1
            w2 = D2 + sa * ua2 - sb * ub2
            d = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2) - vr[ca] - vr[cb]
            if d < best:
                best, bs, bt, br, bsa, bsb = d, s, t, r, sa, sb
        dist[q] = best
        rows[q, 9], rows[q, 10] = bsa, bsb
        rows[q, 11], rows[q, 12] = bs * vhb[va[br]], bt * vhb[vb[br]]
        rows[q, 13], rows[q, 14] = vr[va[br]], vr[vb[br]]
        n2 = 0.0
        for k in range(3):
            xa = B[ga, k] + bsa * U[ga, k]
            xb = B[gb, k] + bsb * U[gb, k]
            rows[q, k], rows[q, 3 + k], rows[q, 6 + k] = xa, xb, xa - xb
            n2 += (xa - xb) ** 2
        if n2 > 1e-30:
            norm = math.sqrt(n2)
            for k in range(3):
                rows[q, 6 + k] /= norm
        else:
            rows[q, 6], rows[q, 7], rows[q, 8] = 0.0, 0.0, 1.0
    motor_length, zone, rho, half = sizes[0], sizes[1], sizes[6], sizes[5]
    Q = leg_plate.shape[0]
    for q in range(Q):
        g, kp = leg_plate[q, 0], leg_plate[q, 1]
        for part in range(2):
            lo = motor_length if part == 1 else 0.0
            hi = L[g] if part == 1 else motor_length
            if leg_plate[q, 2] == 1 and zone > lo:
                lo = zone
            if leg_plate[q, 3] == 1 and L[g] - zone < hi:
                hi = L[g] - zone
            radius = sizes[3] if part == 1 else sizes[2]
            lp_end[q, part] = -1.0
            if hi < lo:
                lp_lb[q, part] = math.inf
                continue
            h0, h1, c, e = 0.0, 0.0, 0.0, 0.0
            for k in range(3):
                a0 = B[g, k] + lo * U[g, k] - p[kp, k]
                dk = (hi - lo) * U[g, k]
                h0 += a0 * R[kp, k, 2]
                h1 += (a0 + dk) * R[kp, k, 2]
                c -= a0 * dk
                e += dk * dk
            s = min(max(c / max(e, 1e-300), 0.0), 1.0)
            w = 0.0
            for k in range(3):
                w += (B[g, k] + (lo + s * (hi - lo)) * U[g, k] - p[kp, k]) ** 2
            slab = max(min(h0, h1), min(-h0, -h1)) - half - radius
            bound = max(math.sqrt(w) - rho - radius, slab)
            if min(h0, h1) > half or max(h0, h1) < -half:  # the part clear of the plate's slab
                hmin = min(abs(h0), abs(h1))
                for end in range(2):
                    hn = h0 if end == 0 else h1
                    sn = lo if end == 0 else hi
                    if abs(hn) > hmin:
                        continue
                    r2 = 0.0
                    for k in range(3):
                        r2 += (B[g, k] + sn * U[g, k] - p[kp, k]) ** 2
                    if r2 - hn * hn <= sizes[4] * sizes[4]:  # over the disc: its face is nearest
                        lp_end[q, part] = end
                        bound = abs(hn) - half - radius
                        break
            lp_lb[q, part] = bound
        near = 0 if lp_lb[q, 0] <= lp_lb[q, 1] else 1
        dist[base + q] = lp_lb[q, near]
        lp_row[q, 0], lp_row[q, 1] = near, lp_end[q, near]
        if lp_end[q, near] >= 0:  # the nearer part's distance, no farther than the other's bound
            exact[base + q] = True
    plate_radius = sizes[4]
    for q in range(plate_pairs.shape[0]):
        ka, kb = plate_pairs[q, 0], plate_pairs[q, 1]
        dc2 = 0.0
        for k in range(3):
            dc2 += (p[ka, k] - p[kb, k]) ** 2
        lb = math.sqrt(dc2) - 2.0 * rho
        for side in range(2):
            first, second = (ka, kb) if side == 0 else (kb, ka)
            cosine, h = 0.0, 0.0
            for k in range(3):
                cosine += R[first, k, 2] * R[second, k, 2]
                h += R[first, k, 2] * (p[second, k] - p[first, k])
            spread = plate_radius * math.sqrt(max(1.0 - cosine * cosine, 0.0)) + half * abs(cosine) + half
            lb = max(lb, abs(h) - spread)
        dist[base + Q + q] = lb


def variant_index(leg_a: np.ndarray, leg_b: np.ndarray, trim: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows of the leg–leg capsule pairs (4 per leg pair: motor/shaft × motor/shaft) as
    variant codes of each leg part (``8 g + 4 part + 2 trim_bottom + trim_top``) for the leg
    pairs ``leg_a``, ``leg_b`` (P,) and their trims (P, 4) (:class:`~assembler_pin.collision.pairs.PairTable`)."""
    parts_a = np.tile(np.array([0, 0, 1, 1]), len(leg_a))
    parts_b = np.tile(np.array([0, 1, 0, 1]), len(leg_a))
    tr = np.repeat(trim.astype(int), 4, axis=0)
    va = np.repeat(leg_a, 4) * 8 + parts_a * 4 + tr[:, 0] * 2 + tr[:, 1]
    vb = np.repeat(leg_b, 4) * 8 + parts_b * 4 + tr[:, 2] * 2 + tr[:, 3]
    return va, vb


@dataclass(frozen=True)
class KernelInputs:
    """The kernel's constants of one configuration.

    Attributes:
        bottom_in, top_in: (G, 3) each leg's joint centres in its bottom and top plate's frame [m].
        va, vb: (4P,) the leg-part variants of every capsule pair (:func:`variant_index`).
        leg_plate: (Q, 4) (leg, plate, trim bottom, trim top) pairs screened (the trims in
            {0, 1}: ``leg.node_zone`` left out at that end); plate_pairs: (S, 2).
        sizes: (7,) :data:`SIZE_NAMES` [m].
    """

    bottom_in: np.ndarray
    top_in: np.ndarray
    va: np.ndarray
    vb: np.ndarray
    leg_plate: np.ndarray
    plate_pairs: np.ndarray
    sizes: np.ndarray


@per_config
def kernel_inputs(cfg: AssemblerConfig) -> KernelInputs:
    """The kernel's constant inputs for a configuration (cached per configuration object)."""
    t = pair_table(cfg)
    va, vb = variant_index(t.leg_a, t.leg_b, t.trim)
    sizes = np.array(
        [
            cfg.leg.motor_length,
            cfg.leg.node_zone,
            cfg.leg.motor_radius,
            cfg.leg.shaft_radius,
            cfg.plate.radius,
            0.5 * cfg.plate.thickness,
            math.hypot(cfg.plate.radius, 0.5 * cfg.plate.thickness),
        ]
    )
    geometry = leg_geometry(cfg)
    bottom = np.ascontiguousarray(geometry.bottom_in_plate.reshape(-1, 3))
    top = np.ascontiguousarray(geometry.top_in_plate.reshape(-1, 3))
    leg_plate = np.ascontiguousarray(np.hstack([t.leg_plate, t.leg_plate_trim.astype(int)]))
    return KernelInputs(bottom, top, va, vb, leg_plate, t.plate_pairs, sizes)


@dataclass(frozen=True)
class OwnPairs:
    """The arrays of the stack's own pairs at one pose (the kernel's outputs).

    Attributes:
        btu: (3, G, 3) every leg's bottom and top joint centres and unit direction, world [m].
        length: (G,) pin-to-pin lengths [m].
        legs: (P, :data:`ROW_WIDTH`) the leg-pair rows (:data:`ROW_XA`...).
        lp: (Q, 2) the lower bounds of each leg's motor and shaft against each screened plate [m].
        lp_end: (Q, 2) where that bound is the distance: 0 or 1 when the part's end at ``lo``
            or ``hi`` lies over the plate's disc, nearest its face, the part clear of the
            plate's slab (the distance is then that end's height over the face less the
            radius); -1 where the bound is only a bound.
        lp_row: (Q, 2) each row's nearer part (:data:`~assembler_pin.collision.bodies.MOTOR`
            or ``SHAFT``) and its ``lp_end``: the row's distance is exact where that is not -1
            (the other part's bound is then no nearer).
    """

    btu: np.ndarray
    length: np.ndarray
    legs: np.ndarray
    lp: np.ndarray
    lp_end: np.ndarray
    lp_row: np.ndarray


def own_pairs(
    inputs: KernelInputs, R: np.ndarray, p: np.ndarray, dist: np.ndarray, at: int, exact: np.ndarray
) -> OwnPairs:
    """The stack's own pairs at the plate poses ``R`` (n+1, 3, 3), ``p`` (n+1, 3) (world
    [m]): the leg pairs' exact distances into ``dist[:P]`` and the screened pairs' lower
    bounds (leg–plate, then plate–plate) into ``dist[at:at + Q + S]`` [m], ``exact[at + q]``
    set True where a leg–plate row's bound is its distance (:attr:`OwnPairs.lp_row`). Every
    returned array is made for this call."""
    G, P, Q = len(inputs.bottom_in), len(inputs.va) // 4, len(inputs.leg_plate)
    btu, length, legs, lp = np.empty((3, G, 3)), np.empty(G), np.empty((P, ROW_WIDTH)), np.empty((Q, 2))
    lp_end, lp_row = np.empty((Q, 2)), np.empty((Q, 2), dtype=np.int64)
    _compiled()(
        R, p, inputs.bottom_in, inputs.top_in, inputs.va, inputs.vb, inputs.leg_plate, inputs.plate_pairs,
        inputs.sizes, at, btu, length, dist, legs, lp, lp_end, lp_row, exact,
    )  # fmt: skip
    return OwnPairs(btu, length, legs, lp, lp_end, lp_row)


def _compiled() -> Any:
    """The compiled :func:`_self_py` (compiled or loaded from numba's cache on first use)."""
    global _kernel
    if _kernel is None:
        import numba  # about a second: paid by the first clearance of a process, not at import

        jit = numba.njit(cache=True, nogil=True)
        globals()["_variant"] = jit(_variant_py)
        _kernel = jit(_self_py)
    return _kernel
