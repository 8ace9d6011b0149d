"""Compiled oil-film kernels of the bearing types (SI units throughout).

Journal position (x, y) and velocity (vx, vy) are relative to the bearing centre (x
horizontal, y vertical up); the shaft turns at Ω (rad/s), Ω > 0 from +x towards +y, the
sense of :func:`rotordiag.simulator._kernels.capone_force`. Every film is the short-bearing
(Ocvirk) solution with the half-Sommerfeld (Gümbel) condition: with H = h/c_f = 1 − X cosθ −
Y sinθ (X, Y the journal position from the film's centre of curvature, in units of its
clearance c_f) the right-hand side of Reynolds' equation is c_f·g(θ), g = a sinθ − b cosθ,
a = ΩX − 2Ẏ, b = ΩY + 2Ẋ, the pressure is positive where g < 0 and the force on the journal is

    F = μ R L³ / (4 c_f²) · 2 ∫_{arc, g<0} g(θ) (cosθ, sinθ) / H³ dθ.

Over the full circle this integral is Capone's closed form (:func:`capone_force_ab`, reused
as it is); over an arc (a lobe, a pad) it is integrated by Gauss–Legendre quadrature on the
arc's positive-pressure part, split at the cavitation angles (where the integrand vanishes)
and into pieces short enough for the film's peak (see :func:`arc_force`).

Parameter arrays (float64) per type code:

* ``PLAIN``: [R, L, c, μ]
* ``LOBED``: [R, L, c, μ, n, then per lobe: x_c, y_c, c_f, θ_start, θ_end]
* ``TILTING_PAD``: [R, L, c, μ, n, then per pad: x_c, y_c, c_f, θ_start, θ_end, t_x, t_y]
  (x_c, y_c the pad's centre of curvature untilted, (t_x, t_y) its tangential unit vector at
  the pivot; a tilt moves the centre by u·c_f·t)
* ``LINEAR``: [n, speeds (n), then per speed: kxx, kxy, kyx, kyy, cxx, cxy, cyx, cyy]
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from rotordiag.core.numerics import NUMBA_OPTIONS

from .._kernels import capone_force_ab

PLAIN, LOBED, TILTING_PAD, LINEAR = 1, 2, 3, 4
HEADER = 5           # R, L, c, μ, n of LOBED and TILTING_PAD
LOBE_STRIDE = 5
PAD_STRIDE = 7
LINEAR_STRIDE = 8

#: Gauss–Legendre points per quadrature piece.
N_GAUSS = 16
_GX, _GW = np.polynomial.legendre.leggauss(N_GAUSS)
GAUSS_X = np.ascontiguousarray(_GX)
GAUSS_W = np.ascontiguousarray(_GW)
N_HALF = N_GAUSS // 2
#: the positive nodes and their weights (the rule is symmetric)
GAUSS_XP = np.ascontiguousarray(_GX[N_HALF:])
GAUSS_WP = np.ascontiguousarray(_GW[N_HALF:])
#: Tilting-pad moment balance: Newton stops when the step in u (pad-centre shift / c_f) is below this.
#: Quadrature pieces are at most PIECE_FACTOR·acosh(1/ε) long (ε the journal eccentricity in the film).
PIECE_FACTOR = 1.5
PAD_TOL = 1e-14
PAD_MAX_ITER = 80
#: Tilting pads: the first trial puts the journal this fraction of the film's half-width towards the trailing edge.
PAD_GUESS = 0.35
#: A Newton step in u below this is applied to the force linearly instead of by a new film evaluation.
PAD_LAST_STEP = 1e-7


@njit(**NUMBA_OPTIONS)
def plain_force(p, x, y, vx, vy, omega):
    """Capone short-bearing force (N) of a plain cylindrical bearing."""
    c = p[2]
    fx, fy = capone_force_ab(x / c, y / c, omega * x / c - 2.0 * vy / c, omega * y / c + 2.0 * vx / c)
    s = p[3] * p[0] * p[1] ** 3 / (4.0 * c * c)
    return s * fx, s * fy


@njit(**NUMBA_OPTIONS)
def _pieces(lo, hi, X, Y, deriv, dXu, dYu, dau, dbu, a, b):
    """∫_lo^hi of 2 g e/H³ (two components) and of its u-derivative (two more) by Gauss–Legendre.

    The integrand's poles sit at an imaginary distance acosh(1/ε) from the real axis; pieces no
    longer than 1.5·acosh(1/ε) keep 16 points within ~1e-11 relative of the closed form.
    """
    eps = math.sqrt(X * X + Y * Y)
    span = hi - lo
    if eps > 1e-3:
        lmax = PIECE_FACTOR * math.acosh(1.0 / eps)
        m = int(math.ceil(span / lmax))
        if m < 1:
            m = 1
    else:
        m = 1
    w = span / m
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    hw = 0.5 * w
    for k in range(m):
        c0 = lo + (k + 0.5) * w
        cc = math.cos(c0)
        sc = math.sin(c0)
        for j in range(N_HALF):
            # the node pair c0 ± hw·x_j shares cos(hw x_j), sin(hw x_j)
            ch = math.cos(hw * GAUSS_XP[j])
            sh = math.sin(hw * GAUSS_XP[j])
            q = hw * GAUSS_WP[j] * 2.0
            for sgn in (1.0, -1.0):
                ct = cc * ch - sgn * sc * sh
                st = sc * ch + sgn * cc * sh
                H = 1.0 - X * ct - Y * st
                g = a * st - b * ct
                ih3 = 1.0 / (H * H * H)
                s0 += q * g * ct * ih3
                s1 += q * g * st * ih3
                if deriv:
                    dH = -(dXu * ct + dYu * st)
                    dg = dau * st - dbu * ct
                    d = (dg - 3.0 * g * dH / H) * ih3
                    s2 += q * d * ct
                    s3 += q * d * st
    return s0, s1, s2, s3


@njit(**NUMBA_OPTIONS)
def arc_force(X, Y, a, b, th1, th2, deriv, dXu, dYu, dau, dbu):
    """Non-dimensional film force 2∫ g e/H³ over the arc [th1, th2] (th2 − th1 ≤ 2π), and, when
    ``deriv``, its derivative along a shift of the film centre (dX/du, dY/du, da/du, db/du).

    NaN when the journal is not inside the film's clearance circle (X² + Y² ≥ 1).
    """
    if not X * X + Y * Y < 1.0:              # also NaN positions
        return math.nan, math.nan, math.nan, math.nan
    n = math.sqrt(a * a + b * b)
    if n == 0.0:
        return 0.0, 0.0, 0.0, 0.0
    if not math.isfinite(n):
        return math.nan, math.nan, math.nan, math.nan
    # g = n sin(θ − θ0), θ0 = atan2(b, a): positive pressure (g < 0) on (θ0 + π, θ0 + 2π)
    s = math.atan2(b, a) + math.pi
    s = th1 + ((s - th1) % (2.0 * math.pi))   # in [th1, th1 + 2π)
    f0 = 0.0
    f1 = 0.0
    f2 = 0.0
    f3 = 0.0
    hi = min(th2, s - math.pi)
    if hi > th1:
        f0, f1, f2, f3 = _pieces(th1, hi, X, Y, deriv, dXu, dYu, dau, dbu, a, b)
    hi = min(th2, s + math.pi)
    if hi > s:
        e0, e1, e2, e3 = _pieces(s, hi, X, Y, deriv, dXu, dYu, dau, dbu, a, b)
        f0 += e0
        f1 += e1
        f2 += e2
        f3 += e3
    return f0, f1, f2, f3


@njit(**NUMBA_OPTIONS)
def lobed_force(p, x, y, vx, vy, omega):
    """Force (N) of a lobed (two-lobe elliptical) bearing: the lobes' films summed."""
    n = int(p[4])
    fx = 0.0
    fy = 0.0
    for k in range(n):
        o = HEADER + LOBE_STRIDE * k
        cf = p[o + 2]
        X = (x - p[o]) / cf
        Y = (y - p[o + 1]) / cf
        a = omega * X - 2.0 * vy / cf
        b = omega * Y + 2.0 * vx / cf
        gx, gy, _, _ = arc_force(X, Y, a, b, p[o + 3], p[o + 4], False, 0.0, 0.0, 0.0, 0.0)
        s = p[3] * p[0] * p[1] ** 3 / (4.0 * cf * cf)
        fx += s * gx
        fy += s * gy
    return fx, fy


@njit(**NUMBA_OPTIONS)
def _pad_ft(X0, Y0, Xd, Yd, omega, u, th1, th2, tx, ty):
    """Pad film force (non-dimensional) with the pad centre shifted by u, its component along t and
    that component's u-derivative, and the force's u-derivative."""
    X = X0 - u * tx
    Y = Y0 - u * ty
    gx, gy, dgx, dgy = arc_force(X, Y, omega * X - 2.0 * Yd, omega * Y + 2.0 * Xd, th1, th2, True,
                                 -tx, -ty, -omega * tx, -omega * ty)
    return gx, gy, gx * tx + gy * ty, dgx * tx + dgy * ty, dgx, dgy


@njit(**NUMBA_OPTIONS)
def pad_force(p, k, x, y, vx, vy, omega):
    """Force (N) of pad ``k`` at its moment equilibrium, and the pad-centre shift u (in c_f).

    Pad inertia and pivot friction are neglected and the pad is taken at rest in tilt
    (quasi-static); for a small tilt the pressure acts through the pad's centre of curvature, so
    moment equilibrium about the pivot means no film force along the tangent t at the pivot. The
    tilt is carried as the shift u·c_f·t of the centre of curvature. F_t(u) has the loaded root
    where it rises through zero (the pad's stable tilt) and a trivial one where the whole pad
    is divergent (no force), on the side of larger u for Ω ≥ 0 (smaller u for Ω < 0, the mirror
    image). The loaded root is bracketed by steps against the sign of F_t from the journal centred
    on the pad (a pad with no film counting as on the trivial root's side), then refined by
    Newton's method with the analytic derivative, bisecting whenever a step leaves the bracket.
    """
    o = HEADER + PAD_STRIDE * k
    cf = p[o + 2]
    th1 = p[o + 3]
    th2 = p[o + 4]
    tx = p[o + 5]
    ty = p[o + 6]
    X0 = (x - p[o]) / cf
    Y0 = (y - p[o + 1]) / cf
    Xd = vx / cf
    Yd = vy / cf
    s = p[3] * p[0] * p[1] ** 3 / (4.0 * cf * cf)
    u0 = X0 * tx + Y0 * ty                 # journal centred tangentially on the pad
    xi2 = X0 * X0 + Y0 * Y0 - u0 * u0      # squared normal distance
    if not xi2 < 1.0:
        return math.nan, math.nan, u0
    half = math.sqrt(1.0 - xi2)            # the film exists for |u − u0| < half
    umin = u0 - half
    umax = u0 + half
    # bracket [lo, hi] with F_t(lo) < 0 ≤ F_t(hi) while iterating
    dry_is_high = omega >= 0.0            # the side of the trivial root (the pad runs dry)
    # start with the journal displaced PAD_GUESS towards the trailing edge (the loaded roots of
    # short-bearing pads lie at 0.2–0.45 c_f for pivot offsets 0.5–0.6 and all loads)
    u = u0 - PAD_GUESS * half if dry_is_high else u0 + PAD_GUESS * half
    gx, gy, ft, dft, dgx, dgy = _pad_ft(X0, Y0, Xd, Yd, omega, u, th1, th2, tx, ty)
    lo = umin
    hi = umax
    have_lo = False
    have_hi = False
    d = 0.05
    for _ in range(PAD_MAX_ITER):
        if not math.isfinite(ft):
            return math.nan, math.nan, u
        dry = gx == 0.0 and gy == 0.0
        if ft < 0.0 or (dry and not dry_is_high):
            lo = u
            have_lo = True
        else:
            hi = u
            have_hi = True
        if ft == 0.0 and not dry:
            break
        if dft > 0.0 and not dry:
            un = u - ft / dft                 # Newton
            if not (lo <= un <= hi):
                un = math.nan
        else:
            un = math.nan
        if not math.isfinite(un):
            if have_lo and have_hi:
                un = 0.5 * (lo + hi)          # bisection inside the bracket
            elif have_lo:
                un = min(u + d, u + 0.5 * (umax - u))
                d *= 2.0
            else:
                un = max(u - d, u - 0.5 * (u - umin))
                d *= 2.0
        if abs(un - u) <= PAD_TOL * (1.0 + abs(u)):
            break
        if abs(un - u) <= PAD_LAST_STEP and lo <= un <= hi and dft > 0.0:
            # the last Newton step is tiny: move the force along it (error ~ step², at round-off)
            gx += dgx * (un - u)
            gy += dgy * (un - u)
            u = un
            break
        u = un
        gx, gy, ft, dft, dgx, dgy = _pad_ft(X0, Y0, Xd, Yd, omega, u, th1, th2, tx, ty)
    return s * gx, s * gy, u


@njit(**NUMBA_OPTIONS)
def pad_fixed_force(p, k, u, x, y, vx, vy, omega):
    """Force (N) of pad ``k`` held at the centre shift u (in c_f), the pad at rest: the pad's own
    film coefficients for the pad-assembly reduction."""
    o = HEADER + PAD_STRIDE * k
    cf = p[o + 2]
    X0 = (x - p[o]) / cf
    Y0 = (y - p[o + 1]) / cf
    gx, gy, _, _, _, _ = _pad_ft(X0, Y0, vx / cf, vy / cf, omega, u, p[o + 3], p[o + 4], p[o + 5], p[o + 6])
    s = p[3] * p[0] * p[1] ** 3 / (4.0 * cf * cf)
    return s * gx, s * gy


@njit(**NUMBA_OPTIONS)
def pad_rate(p, k, u, x, y, vx, vy, omega):
    """Force (N) of pad ``k`` whose tilt is a state (centre shift u, in c_f) and the tilt rate du/dt
    (1/s) that keeps the massless pad in moment equilibrium, F·t = 0 with the pad's own motion in the
    squeeze term: the pad-dynamics alternative to :func:`pad_force` for trains that carry pad states.

    F_t rises with du/dt (the pad's squeeze film damps it); the rate is found by Newton's method
    with the analytic derivative inside a bracket grown from 0. A pad whose film runs dry on one side
    of the bracket is taken to lift off at the rate where it just runs dry; a dry pad keeps its tilt.
    """
    o = HEADER + PAD_STRIDE * k
    cf = p[o + 2]
    th1 = p[o + 3]
    th2 = p[o + 4]
    tx = p[o + 5]
    ty = p[o + 6]
    X = (x - p[o]) / cf - u * tx
    Y = (y - p[o + 1]) / cf - u * ty
    if not X * X + Y * Y < 1.0:
        return math.nan, math.nan, math.nan
    Xd = vx / cf
    Yd = vy / cf
    s = p[3] * p[0] * p[1] ** 3 / (4.0 * cf * cf)
    # relative velocity (Xd − r tx, Yd − r ty): a = ΩX − 2(Yd − r ty), b = ΩY + 2(Xd − r tx)
    r = 0.0
    gx, gy, dgx, dgy = arc_force(X, Y, omega * X - 2.0 * Yd, omega * Y + 2.0 * Xd, th1, th2, True,
                                 0.0, 0.0, 2.0 * ty, -2.0 * tx)
    if not math.isfinite(gx):
        return math.nan, math.nan, math.nan
    if gx == 0.0 and gy == 0.0:
        return 0.0, 0.0, 0.0
    scale = abs(omega) + 2.0 * math.sqrt(Xd * Xd + Yd * Yd) + 1e-300
    lo = -math.inf
    hi = math.inf
    d = 0.05 * scale
    dry_high = 0                       # +1: the dry side is at high rates, −1: at low rates
    for _ in range(PAD_MAX_ITER):
        ft = gx * tx + gy * ty
        dft = dgx * tx + dgy * ty
        dry = gx == 0.0 and gy == 0.0
        if dry:
            if dry_high > 0:
                hi = r
            else:
                lo = r
        elif ft < 0.0:
            lo = r
        else:
            hi = r
        if ft == 0.0 and not dry:
            break
        rn = math.nan
        if dft > 0.0 and not dry:
            rn = r - ft / dft
            if not (lo <= rn <= hi):
                rn = math.nan
        if not math.isfinite(rn):
            if math.isfinite(lo) and math.isfinite(hi):
                rn = 0.5 * (lo + hi)
            elif math.isfinite(lo):
                rn = r + d
                d *= 2.0
                dry_high = 1
            else:
                rn = r - d
                d *= 2.0
                dry_high = -1
        if abs(rn - r) <= PAD_TOL * (scale + abs(r)):
            break
        r = rn
        gx, gy, dgx, dgy = arc_force(X, Y, omega * X - 2.0 * (Yd - r * ty), omega * Y + 2.0 * (Xd - r * tx),
                                     th1, th2, True, 0.0, 0.0, 2.0 * ty, -2.0 * tx)
    return s * gx, s * gy, r


@njit(**NUMBA_OPTIONS)
def tilting_pad_force_states(p, x, y, vx, vy, omega, u, du_dt):
    """Force (N) of a tilting-pad bearing whose pad tilts are states ``u`` (centre shifts in c_f);
    writes each pad's tilt rate into ``du_dt`` (see :func:`pad_rate`)."""
    n = int(p[4])
    fx = 0.0
    fy = 0.0
    for k in range(n):
        gx, gy, r = pad_rate(p, k, u[k], x, y, vx, vy, omega)
        du_dt[k] = r
        fx += gx
        fy += gy
    return fx, fy


@njit(**NUMBA_OPTIONS)
def tilting_pad_force(p, x, y, vx, vy, omega):
    """Force (N) of a tilting-pad bearing: each pad at its own moment equilibrium, summed."""
    n = int(p[4])
    fx = 0.0
    fy = 0.0
    for k in range(n):
        gx, gy, _ = pad_force(p, k, x, y, vx, vy, omega)
        fx += gx
        fy += gy
    return fx, fy


@njit(**NUMBA_OPTIONS)
def linear_force(p, x, y, vx, vy, omega):
    """−K r − C v with K, C interpolated linearly in speed (held constant outside the table)."""
    n = int(p[0])
    base = 1 + n
    if n == 1 or omega <= p[1]:
        o = base
        w = 0.0
        o2 = base
    elif omega >= p[n]:
        o = base + LINEAR_STRIDE * (n - 1)
        o2 = o
        w = 0.0
    else:
        i = 0
        while p[2 + i] < omega:
            i += 1
        w = (omega - p[1 + i]) / (p[2 + i] - p[1 + i])
        o = base + LINEAR_STRIDE * i
        o2 = o + LINEAR_STRIDE
    kxx = (1.0 - w) * p[o] + w * p[o2]
    kxy = (1.0 - w) * p[o + 1] + w * p[o2 + 1]
    kyx = (1.0 - w) * p[o + 2] + w * p[o2 + 2]
    kyy = (1.0 - w) * p[o + 3] + w * p[o2 + 3]
    cxx = (1.0 - w) * p[o + 4] + w * p[o2 + 4]
    cxy = (1.0 - w) * p[o + 5] + w * p[o2 + 5]
    cyx = (1.0 - w) * p[o + 6] + w * p[o2 + 6]
    cyy = (1.0 - w) * p[o + 7] + w * p[o2 + 7]
    return (-(kxx * x + kxy * y + cxx * vx + cxy * vy), -(kyx * x + kyy * y + cyx * vx + cyy * vy))


@njit(**NUMBA_OPTIONS)
def bearing_force(code, params, x, y, vx, vy, omega):
    """Fluid force (fx, fy) in N on the journal of a bearing of type ``code`` (see the module
    docstring); callable from other compiled code. NaN for an unknown code or a journal outside
    the film."""
    if code == PLAIN:
        return plain_force(params, x, y, vx, vy, omega)
    if code == TILTING_PAD:
        return tilting_pad_force(params, x, y, vx, vy, omega)
    if code == LOBED:
        return lobed_force(params, x, y, vx, vy, omega)
    if code == LINEAR:
        return linear_force(params, x, y, vx, vy, omega)
    return math.nan, math.nan
