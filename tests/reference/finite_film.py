"""Slow reference film of finite length: Reynolds' equation in θ and z on an arc, solved by finite
differences, for checking that rotordiag's short-bearing films are its limit L/D → 0.

(1/R²) ∂/∂θ(h³ ∂p/∂θ) + ∂/∂z(h³ ∂p/∂z) = 6μ(Ω ∂h/∂θ + 2 ∂h/∂t), p = 0 on the arc's ends and the
bearing's edges z = ±L/2; negative pressure clipped afterwards (Gümbel, the finite-length form of the
half-Sommerfeld condition the short films use). Conservative 5-point stencil (h³ at the half points in
θ), sparse direct solve; the pressure is exactly quadratic in z as L/D → 0, which the stencil and
Simpson's rule in z reproduce. Independent of rotordiag's kernels (same conventions as
``short_film.film_force``: journal at (x, y), film surface the arc [th1, th2] of a circle of clearance
``cf`` about ``centre`` + ``shift``).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl
from scipy.integrate import simpson


def film_force(R, L, mu, cf, centre, th1, th2, x, y, vx, vy, omega, shift=(0.0, 0.0), n_th=400, n_z=24):
    """Force (N) of the finite-length film on the journal, ``n_th`` × ``n_z`` cells (n_z even)."""
    ex = x - centre[0] - shift[0]
    ey = y - centre[1] - shift[1]
    th = np.linspace(th1, th2, n_th + 1)
    z = np.linspace(-0.5 * L, 0.5 * L, n_z + 1)
    dth, dz = th[1] - th[0], z[1] - z[0]
    ti = th[1:-1]

    def h3(t):
        return (cf - ex * np.cos(t) - ey * np.sin(t)) ** 3

    a_e = h3(ti + 0.5 * dth) / (R * dth) ** 2
    a_w = h3(ti - 0.5 * dth) / (R * dth) ** 2
    a_z = h3(ti) / dz**2
    ni, nj = ti.size, n_z - 1
    i, j = (g.ravel() for g in np.meshgrid(np.arange(ni), np.arange(nj), indexing="ij"))
    k = i * nj + j
    rows, cols, vals = [k], [k], [-(a_e[i] + a_w[i] + 2.0 * a_z[i])]
    for m, kk, v in ((i + 1 < ni, k + nj, a_e[i]), (i > 0, k - nj, a_w[i]),
                     (j + 1 < nj, k + 1, a_z[i]), (j > 0, k - 1, a_z[i])):
        rows.append(k[m])
        cols.append(kk[m])
        vals.append(v[m])
    A = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(ni * nj,) * 2)
    h_th = ex * np.sin(ti) - ey * np.cos(ti)
    h_t = -vx * np.cos(ti) - vy * np.sin(ti)
    rhs = np.repeat(6.0 * mu * (omega * h_th + 2.0 * h_t), nj)
    p = np.zeros((n_th + 1, n_z + 1))
    p[1:-1, 1:-1] = np.maximum(spl.spsolve(A, rhs).reshape(ni, nj), 0.0)
    pbar = simpson(p, x=z, axis=1)
    fx = -R * simpson(pbar * np.cos(th), x=th)
    fy = -R * simpson(pbar * np.sin(th), x=th)
    return float(fx), float(fy)

