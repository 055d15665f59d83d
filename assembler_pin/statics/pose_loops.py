"""The optimizer's per-point values and derivatives as plain loops, compiled by
:mod:`~assembler_pin.statics.pose_kernel`.

The quantities and their derivatives are those of :mod:`assembler_pin.statics.derivatives` (the numpy
reference, whose module docstring states the equilibrium): actuator forces, leg lengths,
deflection cosines, rise and plate angles, and their derivatives with respect to the
**world twist** ``η_k = (v, ω)`` of each plate k = 1..n (``T_k ← exp6(η_k) · T_k``), columns
``6(k-1) .. 6k-1``; plate 0 is fixed. The loops use only scalar arithmetic, :mod:`math` and
``x[i, j, ...]`` indexing of numpy arrays (numpy only to allocate the work arrays).

Each platform's 6×6 system is written in world axes with the moments about its top plate's
origin (the rows of the reference, moments about the world origin, shifted by ``m − p × f``:
better conditioned for tall stacks) and solved by LU with partial pivoting; the same factors
solve the derivative system ``K da = d(rhs) − dK a``.

A leg of platform j moves with plates j (bottom joint) and j+1 (top joint): its local
derivatives have 12 columns, the first six those of plate j (column block j-1, absent for
j = 0), the last six those of plate j+1 (block j).

The functions run interpreted as they are (slowly: the tests use them on one small stack) or
compiled (:mod:`~assembler_pin.statics.pose_kernel` compiles copies whose callees are the compiled ones).

Frames: world poses of plates 0..n; forces [N, tension positive], lengths [m].
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["PARTS"]

# ``consts`` below: the constants of :data:`~assembler_pin.statics_loops.CONSTANT_NAMES`
# (gravity [m/s²], motor and shaft mass [kg], their CoM offsets [m], plate mass [kg],
# payload mass [kg] and offset [m]), from :func:`~assembler_pin.statics_loops.constants`.


def _legs_py(R, p, bottom, top, home, consts, b, t, d, u, L, gp, fp, hb, ht, cosd, rise):
    """Every leg: joint centres b, t, vector d, length L, direction u, gravity across the leg
    gp [m/s²], transverse ball force fp [N], home directions in the world as seen by the
    bottom (hb) and top (ht) plate, deflection cosines cosd (n, 6, 2) and rise (n, 6) [m]."""
    g, ms = consts[0], consts[2]
    lever = consts[3] * consts[1] - consts[4] * ms
    n = R.shape[0] - 1
    for j in range(n):
        for i in range(6):
            for a in range(3):
                b[j, i, a] = p[j, a]
                t[j, i, a] = p[j + 1, a]
                hb[j, i, a] = 0.0
                ht[j, i, a] = 0.0
                for c in range(3):
                    b[j, i, a] += R[j, a, c] * bottom[j, i, c]
                    t[j, i, a] += R[j + 1, a, c] * top[j, i, c]
                    hb[j, i, a] += R[j, a, c] * home[j, i, c]
                    ht[j, i, a] += R[j + 1, a, c] * home[j, i, c]
                d[j, i, a] = t[j, i, a] - b[j, i, a]
            length = math.sqrt(d[j, i, 0] ** 2 + d[j, i, 1] ** 2 + d[j, i, 2] ** 2)
            L[j, i] = length
            for a in range(3):
                u[j, i, a] = d[j, i, a] / length
            gu = -g * u[j, i, 2]
            sf = ms + lever / length
            cb, ct, zu = 0.0, 0.0, 0.0
            for a in range(3):  # g⊥ = g - (g·u) u, g = (0, 0, -g); f⊥ = -s g⊥
                gp[j, i, a] = (-g if a == 2 else 0.0) - gu * u[j, i, a]
                fp[j, i, a] = -sf * gp[j, i, a]
                cb += u[j, i, a] * hb[j, i, a]
                ct += u[j, i, a] * ht[j, i, a]
                zu += R[j, a, 2] * u[j, i, a]
            cosd[j, i, 0], cosd[j, i, 1] = cb, ct
            rise[j, i] = zu * length


def _plate_angles_py(R, p, rest_unit, lam, dlam2, derivs, e, c):
    """λ_k (n,) [rad] of every plate (paper eq. 9) and, with ``derivs``, d(λ_k²) (n, 6n);
    e, c: work vectors (3,)."""
    n = R.shape[0] - 1
    for k in range(n):  # λ of plate k+1: step p_{k+1} - p_k against the rest direction on plate k
        for a in range(3):
            c[a] = R[k, a, 0] * rest_unit[k, 0] + R[k, a, 1] * rest_unit[k, 1] + R[k, a, 2] * rest_unit[k, 2]
            e[a] = p[k + 1, a] - p[k, a]
        length = math.sqrt(e[0] ** 2 + e[1] ** 2 + e[2] ** 2)
        for a in range(3):
            e[a] /= length
        x0, x1, x2 = e[1] * c[2] - e[2] * c[1], e[2] * c[0] - e[0] * c[2], e[0] * c[1] - e[1] * c[0]
        sin_l = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
        cos_l = e[0] * c[0] + e[1] * c[1] + e[2] * c[2]
        lam[k] = math.atan2(sin_l, cos_l)
        if derivs:
            _plate_angle_row(p, k, lam[k], sin_l, cos_l, e, c, length, dlam2)


def _plate_angle_row_py(p, k, lam, sin_l, cos_l, e, c, length, dlam2):
    """Row k of d(λ²): ``2 λ/sinλ · (g_a·dê + g_c·dc)`` with ``g_a = -(c - cosλ ê)``,
    ``g_c = -(ê - cosλ c)``, ê the unit step (3,), c the rest direction (3,) and ``length``
    the step's length [m] (λ/sinλ → 1 at λ = 0)."""
    ratio = lam / sin_l if sin_l > 1e-12 else 1.0
    ga0, ga1, ga2 = -(c[0] - cos_l * e[0]), -(c[1] - cos_l * e[1]), -(c[2] - cos_l * e[2])
    gc0, gc1, gc2 = -(e[0] - cos_l * c[0]), -(e[1] - cos_l * c[1]), -(e[2] - cos_l * c[2])
    e_ga = e[0] * ga0 + e[1] * ga1 + e[2] * ga2
    w0 = (ga0 - e[0] * e_ga) / length  # w = (I - ê êᵀ)/|step| g_a
    w1 = (ga1 - e[1] * e_ga) / length
    w2 = (ga2 - e[2] * e_ga) / length
    f = 2.0 * ratio
    top = 6 * k  # plate k+1 moves p_{k+1} by v + ω × p_{k+1}: w·v + (p × w)·ω
    q0, q1, q2 = p[k + 1, 0], p[k + 1, 1], p[k + 1, 2]
    dlam2[k, top], dlam2[k, top + 1], dlam2[k, top + 2] = f * w0, f * w1, f * w2
    dlam2[k, top + 3] = f * (q1 * w2 - q2 * w1)
    dlam2[k, top + 4] = f * (q2 * w0 - q0 * w2)
    dlam2[k, top + 5] = f * (q0 * w1 - q1 * w0)
    if k >= 1:  # plate k moves p_k (against the step) and turns c: (c × g_c)·ω
        q0, q1, q2 = p[k, 0], p[k, 1], p[k, 2]
        dlam2[k, top - 6], dlam2[k, top - 5], dlam2[k, top - 4] = -f * w0, -f * w1, -f * w2
        dlam2[k, top - 3] = f * ((c[1] * gc2 - c[2] * gc1) - (q1 * w2 - q2 * w1))
        dlam2[k, top - 2] = f * ((c[2] * gc0 - c[0] * gc2) - (q2 * w0 - q0 * w2))
        dlam2[k, top - 1] = f * ((c[0] * gc1 - c[1] * gc0) - (q0 * w1 - q1 * w0))


def _lu_factor_py(K, piv):
    """LU with partial pivoting of K (6×6) in place, row swaps in piv; False when a pivot is
    exactly zero or not finite (the system is singular)."""
    for c in range(6):
        best = c
        for r in range(c + 1, 6):
            if abs(K[r, c]) > abs(K[best, c]):
                best = r
        piv[c] = best
        if K[best, c] == 0.0 or not math.isfinite(K[best, c]):
            return False
        if best != c:
            for q in range(6):
                K[c, q], K[best, q] = K[best, q], K[c, q]
        for r in range(c + 1, 6):
            f = K[r, c] / K[c, c]
            K[r, c] = f
            for q in range(c + 1, 6):
                K[r, q] -= f * K[c, q]
    return True


def _lu_solve_py(K, piv, x):
    """Solve with the factors of :func:`_lu_factor_py`, the right-hand side x (6,) in place."""
    for c in range(6):
        if piv[c] != c:
            x[c], x[piv[c]] = x[piv[c]], x[c]
    for r in range(1, 6):
        for q in range(r):
            x[r] -= K[r, q] * x[q]
    for r in range(5, -1, -1):
        for q in range(r + 1, 6):
            x[r] -= K[r, q] * x[q]
        x[r] /= K[r, r]


def _platform_py(p, j, t, u, fp, up_w, up_m, K, piv, a):
    """Platform j's 6×6 system (rows ``[u; (t - p) × u]``, a column per leg, moments about
    plate j+1's origin p) and its right-hand side, factored and solved for the axial ball-force
    components a (6,) [N]. ``up_w`` [N, downward] and ``up_m`` (3,) [N·m, about the world
    origin]: the weight above plate j+1. False when the system is singular."""
    px, py, pz = p[j + 1, 0], p[j + 1, 1], p[j + 1, 2]
    f0, f1, f2 = 0.0, 0.0, -up_w
    m0, m1, m2 = up_m[0], up_m[1], up_m[2]
    for i in range(6):
        tx, ty, tz = t[j, i, 0], t[j, i, 1], t[j, i, 2]
        fx, fy, fz = fp[j, i, 0], fp[j, i, 1], fp[j, i, 2]
        f0, f1, f2 = f0 - fx, f1 - fy, f2 - fz
        m0 -= ty * fz - tz * fy
        m1 -= tz * fx - tx * fz
        m2 -= tx * fy - ty * fx
        ux, uy, uz = u[j, i, 0], u[j, i, 1], u[j, i, 2]
        rx, ry, rz = tx - px, ty - py, tz - pz
        K[0, i], K[1, i], K[2, i] = ux, uy, uz
        K[3, i], K[4, i], K[5, i] = ry * uz - rz * uy, rz * ux - rx * uz, rx * uy - ry * ux
    a[0], a[1], a[2] = f0, f1, f2
    a[3] = m0 - (py * f2 - pz * f1)
    a[4] = m1 - (pz * f0 - px * f2)
    a[5] = m2 - (px * f1 - py * f0)
    if not _lu_factor(K, piv):
        return False
    _lu_solve(K, piv, a)
    return True


def _level_py(p, j, b, t, u, consts, up_m):
    """Add level j (plate j for j ≥ 1, the legs of platform j) to the weight's moment about
    the world origin ``up_m`` (3,) [N·m]; returns the level's weight [N]. A weight w at x has
    the moment x × (0, 0, -w) = (-x_y w, x_x w, 0)."""
    g, mm, ms, mc, sc, mplate = consts[0], consts[1], consts[2], consts[3], consts[4], consts[5]
    weight = 6.0 * (mm + ms) * g
    for i in range(6):
        cx = mm * (b[j, i, 0] + mc * u[j, i, 0]) + ms * (t[j, i, 0] - sc * u[j, i, 0])
        cy = mm * (b[j, i, 1] + mc * u[j, i, 1]) + ms * (t[j, i, 1] - sc * u[j, i, 1])
        up_m[0] -= cy * g
        up_m[1] += cx * g
    if j >= 1:
        up_m[0] -= p[j, 1] * mplate * g
        up_m[1] += p[j, 0] * mplate * g
        weight += mplate * g
    return weight


def _point_column_py(x, c, col):
    """Column c (0..5) of ``[I, -[x]×]``: how a world twist's component c moves the point x."""
    if c < 3:
        col[0], col[1], col[2] = 0.0, 0.0, 0.0
        col[c] = 1.0
    elif c == 3:
        col[0], col[1], col[2] = 0.0, -x[2], x[1]
    elif c == 4:
        col[0], col[1], col[2] = x[2], 0.0, -x[0]
    else:
        col[0], col[1], col[2] = -x[1], x[0], 0.0


def _leg_column_py(b, t, u, L, j, i, c, dd, du):
    """Local column c (0..11) of leg (j, i): the change dd (3,) of its vector [m] and du (3,)
    of its direction; returns the change of its length [m]. Columns 0..5 move the bottom
    joint (plate j), 6..11 the top joint (plate j+1)."""
    if c < 6:
        _point_column(b[j, i], c, dd)
        dd[0], dd[1], dd[2] = -dd[0], -dd[1], -dd[2]
    else:
        _point_column(t[j, i], c - 6, dd)
    dl = u[j, i, 0] * dd[0] + u[j, i, 1] * dd[1] + u[j, i, 2] * dd[2]
    for a in range(3):
        du[a] = (dd[a] - u[j, i, a] * dl) / L[j, i]
    return dl


def _leg_measures_py(R, j, i, c, col, dl, dd, du, d, u, hb, ht, dL, dcos, drise):
    """Length, deflection-cosine and rise derivatives of leg (j, i) in global column ``col``
    from its local column c: ``d(u·h) = h·du + (h × u)·ω`` for the plate h turns with, and
    ``d(z·d) = z·dd + (z × d)·ω`` for the bottom plate's z."""
    dL[j, i, col] = dl
    cb = hb[j, i, 0] * du[0] + hb[j, i, 1] * du[1] + hb[j, i, 2] * du[2]
    ct = ht[j, i, 0] * du[0] + ht[j, i, 1] * du[1] + ht[j, i, 2] * du[2]
    dr = R[j, 0, 2] * dd[0] + R[j, 1, 2] * dd[1] + R[j, 2, 2] * dd[2]
    if c >= 3 and c < 6:  # the bottom plate turns: the bottom joint's home direction and its z
        a = c - 3
        b1, b2 = (a + 1) % 3, (a + 2) % 3
        cb += hb[j, i, b1] * u[j, i, b2] - hb[j, i, b2] * u[j, i, b1]
        dr += R[j, b1, 2] * d[j, i, b2] - R[j, b2, 2] * d[j, i, b1]
    elif c >= 9:  # the top plate turns: the top joint's home direction
        a = c - 9
        b1, b2 = (a + 1) % 3, (a + 2) % 3
        ct += ht[j, i, b1] * u[j, i, b2] - ht[j, i, b2] * u[j, i, b1]
    dcos[j, i, 0, col], dcos[j, i, 1, col] = cb, ct
    drise[j, i, col] = dr


def _platform_rows_py(R, j, consts, b, t, d, u, L, gp, fp, hb, ht, a, M, dd, du, dt, dF, dL, dcos, drise):
    """Add the local terms of platform j's legs to ``M`` (6, 6n) = d(rhs) − dK a (moments about
    the world origin), and fill their length, deflection, rise and shaft-weight force columns."""
    g, ms = consts[0], consts[2]
    lever = consts[3] * consts[1] - consts[4] * ms
    first = 0 if j >= 1 else 6
    for i in range(6):
        ux, uy, uz = u[j, i, 0], u[j, i, 1], u[j, i, 2]
        tx, ty, tz = t[j, i, 0], t[j, i, 1], t[j, i, 2]
        fx, fy, fz = fp[j, i, 0], fp[j, i, 1], fp[j, i, 2]
        gu = -g * uz
        sf = ms + lever / L[j, i]
        for c in range(first, 12):
            col = 6 * (j - 1) + c
            dl = _leg_column(b, t, u, L, j, i, c, dd, du)
            _leg_measures(R, j, i, c, col, dl, dd, du, d, u, hb, ht, dL, dcos, drise)
            if c < 6:
                dt[0], dt[1], dt[2] = 0.0, 0.0, 0.0
            else:
                dt[0], dt[1], dt[2] = dd[0], dd[1], dd[2]
            dgu = -g * du[2]
            ds = -lever / L[j, i] ** 2 * dl
            # d f⊥ = -(ds g⊥ + s d g⊥), d g⊥ = -(dgu u + gu du)
            q0 = -(ds * gp[j, i, 0] - sf * (dgu * ux + gu * du[0]))
            q1 = -(ds * gp[j, i, 1] - sf * (dgu * uy + gu * du[1]))
            q2 = -(ds * gp[j, i, 2] - sf * (dgu * uz + gu * du[2]))
            ai = a[i]
            M[0, col] -= q0 + ai * du[0]
            M[1, col] -= q1 + ai * du[1]
            M[2, col] -= q2 + ai * du[2]
            # d(t × f⊥) = dt × f⊥ + t × d f⊥ ; d(t × u) = dt × u + t × du
            M[3, col] -= (
                dt[1] * fz - dt[2] * fy + ty * q2 - tz * q1 + ai * (dt[1] * uz - dt[2] * uy + ty * du[2] - tz * du[1])
            )
            M[4, col] -= (
                dt[2] * fx - dt[0] * fz + tz * q0 - tx * q2 + ai * (dt[2] * ux - dt[0] * uz + tz * du[0] - tx * du[2])
            )
            M[5, col] -= (
                dt[0] * fy - dt[1] * fx + tx * q1 - ty * q0 + ai * (dt[0] * uy - dt[1] * ux + tx * du[1] - ty * du[0])
            )
            dF[j, i, col] = ms * dgu


def _platform_derivatives_py(
    R, p, j, consts, b, t, d, u, L, gp, fp, hb, ht, K, piv, a, dup, M, work, dF, dL, dcos, drise
):
    """Derivatives of platform j: ``K da = d(rhs) − dK a`` with the weight's moment above
    (``dup`` (3, 6n), about the world origin) and the legs' local terms, shifted to moments
    about plate j+1's origin like the values and solved with the factors of K; fills dF, dL,
    dcos, drise of its legs. ``work``: (4, 6) scratch."""
    C = dup.shape[1]
    first = max(0, 6 * (j - 1))
    for col in range(first, C):
        for r in range(3):
            M[r, col] = 0.0
            M[3 + r, col] = dup[r, col]
    _platform_rows(R, j, consts, b, t, d, u, L, gp, fp, hb, ht, a, M, work[0], work[1], work[2], dF, dL, dcos, drise)
    x = work[3]
    px, py, pz = p[j + 1, 0], p[j + 1, 1], p[j + 1, 2]
    for col in range(first, C):
        f0, f1, f2 = M[0, col], M[1, col], M[2, col]
        x[0], x[1], x[2] = f0, f1, f2
        x[3] = M[3, col] - (py * f2 - pz * f1)
        x[4] = M[4, col] - (pz * f0 - px * f2)
        x[5] = M[5, col] - (px * f1 - py * f0)
        _lu_solve(K, piv, x)
        for i in range(6):
            dF[j, i, col] += x[i]


def _weight_moment_column_py(x, c, w, dup, col, work):
    """Add the change of the moment of a weight w [N] at the point x, moved by a world twist's
    component c, to ``dup[:, col]``: ``dx × (0, 0, -g) = (-g dx_y, g dx_x, 0)`` times w / g."""
    _point_column(x, c, work)
    dup[0, col] -= w * work[1]
    dup[1, col] += w * work[0]


def _top_level_derivatives_py(R, p, consts, dup, work):
    """``dup`` (3, 6n) [N·m]: the derivative of the moment of level n (plate n and the payload)
    about the world origin."""
    g, mplate, mpay, off = consts[0], consts[5], consts[6], consts[7]
    n = R.shape[0] - 1
    for r in range(3):
        work[1, r] = p[n, r] + R[n, r, 2] * off  # the payload's centre of mass
    for c in range(6):
        col = 6 * (n - 1) + c
        _weight_moment_column(p[n], c, mplate * g, dup, col, work[0])
        _weight_moment_column(work[1], c, mpay * g, dup, col, work[0])


def _level_derivatives_py(p, j, consts, b, t, u, L, dup, work):
    """Add the derivative of level j's moment (plate j, the legs of platform j) about the world
    origin to ``dup`` (3, 6n): each leg's motor at b + c_m u and shaft at t − c_s u."""
    g, mm, ms, mc, sc, mplate = consts[0], consts[1], consts[2], consts[3], consts[4], consts[5]
    dd, du = work[0], work[1]
    first = 0 if j >= 1 else 6
    for i in range(6):
        for c in range(first, 12):
            col = 6 * (j - 1) + c
            _leg_column(b, t, u, L, j, i, c, dd, du)
            # mm (db + c_m du) + ms (dt - c_s du); dd = dt - db, one of them zero
            wb = -mm if c < 6 else ms
            x0 = wb * dd[0] + (mm * mc - ms * sc) * du[0]
            x1 = wb * dd[1] + (mm * mc - ms * sc) * du[1]
            dup[0, col] -= g * x1
            dup[1, col] += g * x0
    if j >= 1:
        for c in range(6):
            _weight_moment_column(p[j], c, mplate * g, dup, 6 * (j - 1) + c, work[0])


def _pose_py(
    R, p, bottom, top, home, rest_unit, consts, derivs, forces, L, cosd, rise, lam, dF, dL, dcos, drise, dlam2
):
    """The whole pass of one stack (R (n+1, 3, 3), p (n+1, 3)): forces (n, 6), lengths (n, 6),
    deflection cosines (n, 6, 2), rise (n, 6) and plate angles (n,) and, with ``derivs``, their
    derivatives (last axis 6n, zero-filled by the caller). Returns False when a platform's
    system is singular (its forces NaN, the derivatives not filled)."""
    n = R.shape[0] - 1
    b, t, d, u = np.empty((n, 6, 3)), np.empty((n, 6, 3)), np.empty((n, 6, 3)), np.empty((n, 6, 3))
    gp, fp, hb, ht = np.empty((n, 6, 3)), np.empty((n, 6, 3)), np.empty((n, 6, 3)), np.empty((n, 6, 3))
    work = np.empty((4, 6))
    _legs(R, p, bottom, top, home, consts, b, t, d, u, L, gp, fp, hb, ht, cosd, rise)
    _plate_angles(R, p, rest_unit, lam, dlam2, derivs, work[0], work[1])
    g, ms, mplate, mpay, off = consts[0], consts[2], consts[5], consts[6], consts[7]
    K, piv, a, up_m = np.empty((6, 6)), np.empty(6, np.int64), np.empty(6), np.zeros(3)
    columns = 6 * n if derivs else 1
    dup, M = np.zeros((3, columns)), np.empty((6, columns))
    up_w = (mplate + mpay) * g  # level n: plate n and the payload (at p_n + R_n z·offset)
    up_m[0] = -(p[n, 1] * mplate + (p[n, 1] + R[n, 1, 2] * off) * mpay) * g
    up_m[1] = (p[n, 0] * mplate + (p[n, 0] + R[n, 0, 2] * off) * mpay) * g
    if derivs:
        _top_level_derivatives(R, p, consts, dup, work)
    ok = True
    for j in range(n - 1, -1, -1):  # top down: the weight above plate j+1 is levels j+1..n
        if _platform(p, j, t, u, fp, up_w, up_m, K, piv, a):
            for i in range(6):
                forces[j, i] = a[i] - ms * g * u[j, i, 2]
            if derivs and ok:
                _platform_derivatives(
                    R, p, j, consts, b, t, d, u, L, gp, fp, hb, ht, K, piv, a, dup, M, work, dF, dL, dcos, drise
                )
        else:
            ok = False
            for i in range(6):
                forces[j, i] = math.nan
        if j >= 1:
            if derivs:
                _level_derivatives(p, j, consts, b, t, u, L, dup, work)
            up_w += _level(p, j, b, t, u, consts, up_m)
    return ok


# The callees of the loops; the compiled kernel binds the same names to compiled copies.
_legs, _plate_angle_row, _lu_factor, _lu_solve, _point_column = (
    _legs_py,
    _plate_angle_row_py,
    _lu_factor_py,
    _lu_solve_py,
    _point_column_py,
)
_leg_column, _leg_measures, _platform_rows, _weight_moment_column = (
    _leg_column_py,
    _leg_measures_py,
    _platform_rows_py,
    _weight_moment_column_py,
)
_plate_angles, _platform, _level, _platform_derivatives = (
    _plate_angles_py,
    _platform_py,
    _level_py,
    _platform_derivatives_py,
)
_top_level_derivatives, _level_derivatives = _top_level_derivatives_py, _level_derivatives_py

#: Every loop in callee-first order, under the name its callers use: the compiled kernel
#: compiles them in this order, so each caller sees its callees compiled.
PARTS = (
    ("_point_column", _point_column_py),
    ("_lu_factor", _lu_factor_py),
    ("_lu_solve", _lu_solve_py),
    ("_legs", _legs_py),
    ("_plate_angle_row", _plate_angle_row_py),
    ("_plate_angles", _plate_angles_py),
    ("_platform", _platform_py),
    ("_level", _level_py),
    ("_leg_column", _leg_column_py),
    ("_leg_measures", _leg_measures_py),
    ("_platform_rows", _platform_rows_py),
    ("_platform_derivatives", _platform_derivatives_py),
    ("_weight_moment_column", _weight_moment_column_py),
    ("_top_level_derivatives", _top_level_derivatives_py),
    ("_level_derivatives", _level_derivatives_py),
    ("_pose", _pose_py),
)
