"""Orbit shape of the filtered 1X + 2X orbit of one bearing (exact from the order coefficients)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from . import _config as cfg
from ._kernels import coarse_diameter

__all__ = ["OrbitShape", "OrbitArrays", "orbit_shape", "orbit_shapes", "orbit_arrays"]


@dataclass(frozen=True)
class OrbitShape:
    """Shape figures of a closed orbit ``x(θ) + j y(θ)`` over one revolution.

    Attributes
    ----------
    pp_um : float
        Peak-to-peak: the largest distance between two points of the orbit (its diameter).
    area_um2 : float
        Signed enclosed area ½∮(x dy − y dx): > 0 for forward (counter-clockwise, with the
        shaft) travel; loops count with their winding number.
    ellipticity : float
        sqrt(λ_min / λ_max) of the orbit's second-moment matrix about its centre
        (1 circle, 0 straight line; for a pure 1X ellipse the minor/major axis ratio).
    turning_number : int
        Total rotation of the tangent over one revolution / 2π: +1 a simple forward orbit,
        +2 a forward orbit with one inner loop, 0 a figure-8, −1/−2 the same backward.
    concavity : float
        Fraction of the tangent's total turning that goes against the orbit's overall
        direction: 0 for a convex (elliptical) orbit, > 0 for a banana/kidney shape that is
        forming a loop, 0.5 for a symmetric figure-8.
    points_um : ndarray, shape (ORBIT_GRID, 2)
        The orbit on a uniform θ grid (for plotting).
    """

    pp_um: float
    area_um2: float
    ellipticity: float
    turning_number: int
    concavity: float
    points_um: np.ndarray

    @property
    def has_loop(self) -> bool:
        """True for an inner loop or a figure-8 (turning number other than ±1)."""
        return abs(self.turning_number) != 1


@lru_cache(maxsize=8)
def _grid_basis(m: int, k_max: int) -> tuple[np.ndarray, np.ndarray]:
    """e^{jkθ} and jk·e^{jkθ} on the uniform grid, shape (m, k_max) (cached, read-only)."""
    k = np.arange(1, k_max + 1)
    e = np.exp(1j * np.outer(2 * np.pi * np.arange(m) / m, k))
    de = e * (1j * k)
    e.flags.writeable = False
    de.flags.writeable = False
    return e, de


@dataclass(frozen=True)
class OrbitArrays:
    """The figures of :class:`OrbitShape` for several orbits, one array entry per orbit."""

    pp: np.ndarray
    area: np.ndarray
    ellipticity: np.ndarray
    turning: np.ndarray
    concavity: np.ndarray
    x: np.ndarray               # (n_orbits, ORBIT_GRID)
    y: np.ndarray

    def shape(self, b: int) -> OrbitShape:
        """Orbit ``b`` as an :class:`OrbitShape`."""
        return OrbitShape(float(self.pp[b]), float(self.area[b]), float(self.ellipticity[b]),
                          int(self.turning[b]), float(self.concavity[b]), np.column_stack([self.x[b], self.y[b]]))


def orbit_shapes(cx: np.ndarray, cy: np.ndarray, whirl_hint: np.ndarray | None = None) -> list[OrbitShape]:
    """Shapes of several orbits ``x = Re Σ cx[b,k] e^{jkθ}``, ``y = Re Σ cy[b,k] e^{jkθ}`` at once.

    Parameters
    ----------
    cx, cy : ndarray, complex, shape (n_orbits, K)
        Order coefficients (zero-to-peak) of x and y for orders 1..K (the constant is irrelevant).
    whirl_hint : ndarray, shape (n_orbits,), optional
        Direction used for ``concavity`` when the turning number is 0 (figure-8): the sign of
        the 1X whirl (default +1).
    """
    arr = orbit_arrays(cx, cy, whirl_hint)
    return [arr.shape(b) for b in range(arr.pp.size)]


def orbit_arrays(cx: np.ndarray, cy: np.ndarray, whirl_hint: np.ndarray | None = None) -> OrbitArrays:
    """:func:`orbit_shapes` as arrays over the orbits (no per-orbit objects)."""
    cx = np.atleast_2d(cx)
    cy = np.atleast_2d(cy)
    nb, k_max = cx.shape
    m = cfg.ORBIT_GRID
    e, de = _grid_basis(m, k_max)
    x = (cx @ e.T).real                  # (nb, m)
    y = (cy @ e.T).real
    dx = (cx @ de.T).real
    dy = (cy @ de.T).real
    # signed area: trapezoid rule on a periodic trigonometric polynomial is exact
    area = np.pi / m * np.sum(x * dy - y * dx, axis=1)
    # second moments about the centre (exact on the uniform grid); 2×2 eigenvalues in closed form
    xc = x - x.mean(axis=1, keepdims=True)
    yc = y - y.mean(axis=1, keepdims=True)
    sxx, syy, sxy = np.mean(xc * xc, axis=1), np.mean(yc * yc, axis=1), np.mean(xc * yc, axis=1)
    half_tr = 0.5 * (sxx + syy)
    disc = np.sqrt(np.maximum(0.25 * (sxx - syy) ** 2 + sxy ** 2, 0.0))
    lam_max, lam_min = half_tr + disc, np.maximum(half_tr - disc, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        ellipticity = np.where(lam_max > 0, np.sqrt(lam_min / lam_max), np.nan)
    # tangent turning
    psi = np.arctan2(dy, dx)
    dpsi = np.diff(psi, axis=1, append=psi[:, :1])
    dpsi = (dpsi + np.pi) % (2 * np.pi) - np.pi
    turning = np.round(dpsi.sum(axis=1) / (2 * np.pi)).astype(int)
    hint = np.ones(nb) if whirl_hint is None else np.where(np.sign(whirl_hint) == 0, 1.0, np.sign(whirl_hint))
    s = np.where(turning != 0, np.sign(turning), hint)
    absturn = np.abs(dpsi).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        concavity = np.where(absturn > 0, np.maximum(0.0, -s[:, None] * dpsi).sum(axis=1) / absturn, np.nan)
    # diameter: coarse pairwise search on every third grid point, then a fine local search
    xs, ys = x[:, ::3], y[:, ::3]
    flat = np.empty(nb, dtype=np.int64)
    d2max = np.empty(nb)
    coarse_diameter(np.ascontiguousarray(xs), np.ascontiguousarray(ys), flat, d2max)   # pairs of the m/3 points
    i, j = np.divmod(flat, xs.shape[1])
    step = 3 * 2 * np.pi / m
    fine = np.linspace(-step, step, 65)
    ks = np.arange(1, k_max + 1)
    ti = (2 * np.pi * 3 * i / m)[:, None] + fine[None, :]       # (nb, 65)
    tj = (2 * np.pi * 3 * j / m)[:, None] + fine[None, :]
    ei = np.exp(1j * ti[:, :, None] * ks)                       # (nb, 65, K)
    ej = np.exp(1j * tj[:, :, None] * ks)
    zi = np.einsum("bfk,bk->bf", ei, cx).real + 1j * np.einsum("bfk,bk->bf", ei, cy).real
    zj = np.einsum("bfk,bk->bf", ej, cx).real + 1j * np.einsum("bfk,bk->bf", ej, cy).real
    pp = np.maximum(np.abs(zi[:, :, None] - zj[:, None, :]).reshape(nb, -1).max(axis=1),
                    np.sqrt(d2max))
    return OrbitArrays(pp, area, ellipticity, turning, concavity, x, y)


def orbit_shape(cx: np.ndarray, cy: np.ndarray, whirl_hint: float = 1.0) -> OrbitShape:
    """Shape of one orbit (see :func:`orbit_shapes`); ``cx``, ``cy`` of shape (K,)."""
    return orbit_shapes(np.asarray(cx)[None, :], np.asarray(cy)[None, :], np.array([whirl_hint]))[0]
