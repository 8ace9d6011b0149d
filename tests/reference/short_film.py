"""Slow, plain reference for the bearing films: the short-bearing (Ocvirk) pressure written out
from Reynolds' equation and integrated with scipy's adaptive quadrature, cavitated by clipping
negative pressure (half-Sommerfeld), on any arc; a tilting pad's tilt found by ``brentq`` on the
moment of the pressure about the pivot point itself. Independent of rotordiag's kernels.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq


def film_force(R, L, mu, cf, centre, th1, th2, x, y, vx, vy, omega, shift=(0.0, 0.0)):
    """Force (N) of a film of clearance ``cf`` whose surface is the arc [th1, th2] of a circle
    centred at ``centre`` (+ ``shift``), on a journal at (x, y) moving at (vx, vy).

    Reynolds (short bearing): d/dz(h³ dp/dz) = 6μ(Ω ∂h/∂θ + 2 ∂h/∂t), p(±L/2) = 0, so
    p = 3μ(Ω h_θ + 2 h_t)(z² − L²/4)/h³, and ∫p dz = −μL³(Ω h_θ + 2 h_t)/(2h³).
    """
    ex = x - centre[0] - shift[0]
    ey = y - centre[1] - shift[1]

    def pbar(th):
        h = cf - ex * math.cos(th) - ey * math.sin(th)
        h_th = ex * math.sin(th) - ey * math.cos(th)
        h_t = -vx * math.cos(th) - vy * math.sin(th)
        return max(0.0, -mu * L**3 * (omega * h_th + 2.0 * h_t) / (2.0 * h**3))

    # break the quadrature where the film cavitates (the pressure's kink), found by brentq on a grid
    def rhs(th):
        return omega * (ex * math.sin(th) - ey * math.cos(th)) + 2.0 * (-vx * math.cos(th) - vy * math.sin(th))

    grid = np.linspace(th1, th2, 721)
    vals = [rhs(t) for t in grid]
    kinks = [brentq(rhs, grid[i], grid[i + 1], xtol=1e-15) for i in range(len(grid) - 1) if vals[i] * vals[i + 1] < 0]
    opts = dict(limit=400, epsabs=0.0, epsrel=1e-12, points=kinks or None)
    fx = -R * quad(lambda t: pbar(t) * math.cos(t), th1, th2, **opts)[0]
    fy = -R * quad(lambda t: pbar(t) * math.sin(t), th1, th2, **opts)[0]
    return fx, fy, pbar


def pad_moment(R, L, mu, cf, centre, th1, th2, pivot_angle, x, y, omega, shift):
    """Moment (N·m) of the film pressure on the pad about its pivot, a point on the pad's back
    1.5 R from its centre of curvature along the pivot direction, summed point by point."""
    fx, fy, pbar = film_force(R, L, mu, cf, centre, th1, th2, x, y, 0.0, 0.0, omega, shift)
    # pivot point: on the pad's back, along the pivot direction from the pad's centre of curvature
    px = centre[0] + shift[0] + 1.5 * R * math.cos(pivot_angle)
    py = centre[1] + shift[1] + 1.5 * R * math.sin(pivot_angle)

    def m(th):
        # force on the pad at the surface point (R cosθ, R sinθ) about the curvature centre: +p e(θ)
        sx = centre[0] + shift[0] + R * math.cos(th)
        sy = centre[1] + shift[1] + R * math.sin(th)
        p = pbar(th)
        return ((sx - px) * p * math.sin(th) - (sy - py) * p * math.cos(th)) * R

    return quad(m, th1, th2, limit=400, epsabs=0.0, epsrel=1e-12)[0], (fx, fy)


def tilting_pad_static_force(R, L, mu, c, cp, pivots, arcs, x, y, omega, n_scan=400):
    """Static force of a tilting-pad bearing, each pad's tilt (a shift of its centre of curvature
    perpendicular to the pivot line) from a root of its moment about the pivot (``brentq``)."""
    fx = fy = 0.0
    for piv, (th1, th2) in zip(pivots, arcs, strict=True):
        e = np.array([math.cos(piv), math.sin(piv)])
        t = np.array([-e[1], e[0]])
        centre = -(cp - c) * e
        # journal relative to the untilted centre, tangential component
        rel = np.array([x, y]) - centre
        u0 = rel @ t
        half = math.sqrt(max(cp**2 - (rel @ e) ** 2, 0.0))
        us = np.linspace(u0 - 0.999 * half, u0 + 0.999 * half, n_scan)
        vals = [pad_moment(R, L, mu, cp, centre, th1, th2, piv, x, y, omega, tuple(u * t))[0] for u in us]
        loaded = [abs(v) > 0 for v in vals]
        roots = [i for i in range(len(us) - 1) if loaded[i] and loaded[i + 1] and vals[i] * vals[i + 1] < 0]
        if not roots:
            continue
        i = roots[0]
        u = brentq(lambda s: pad_moment(R, L, mu, cp, centre, th1, th2, piv, x, y, omega, tuple(s * t))[0],
                   us[i], us[i + 1], xtol=1e-16 * cp, rtol=1e-14)
        f = film_force(R, L, mu, cp, centre, th1, th2, x, y, 0.0, 0.0, omega, tuple(u * t))
        fx += f[0]
        fy += f[1]
    return fx, fy
