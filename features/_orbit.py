"""Orbit shape of the filtered 1X + 2X orbit of one bearing (exact from the order coefficients)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from . import _config as cfg

__all__ = ["OrbitShape", "orbit_shape"]


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
def _grid_basis(m: int, k_max: int) -> np.ndarray:
    e = np.exp(1j * np.outer(2 * np.pi * np.arange(m) / m, np.arange(1, k_max + 1)))
    e.flags.writeable = False
    return e


def _eval(cx: np.ndarray, cy: np.ndarray, theta: np.ndarray | None) -> tuple[np.ndarray, ...]:
    k = np.arange(1, cx.size + 1)
    e = _grid_basis(cfg.ORBIT_GRID, cx.size) if theta is None else np.exp(1j * np.outer(theta, k))
    x = (e @ cx).real
    y = (e @ cy).real
    dx = (e @ (1j * k * cx)).real
    dy = (e @ (1j * k * cy)).real
    return x, y, dx, dy


def orbit_shape(cx: np.ndarray, cy: np.ndarray, whirl_hint: float = 1.0) -> OrbitShape:
    """Shape of the orbit ``x = Re Σ cx_k e^{jkθ}``, ``y = Re Σ cy_k e^{jkθ}``.

    Parameters
    ----------
    cx, cy : ndarray, complex, shape (K,)
        Order coefficients (zero-to-peak) of x and y for orders 1..K (the constant is irrelevant).
    whirl_hint : float
        Direction used for ``concavity`` when the turning number is 0 (figure-8): the sign of
        the 1X whirl.
    """
    m = cfg.ORBIT_GRID
    theta = 2 * np.pi * np.arange(m) / m
    x, y, dx, dy = _eval(cx, cy, None)
    # signed area: trapezoid rule on a periodic trigonometric polynomial is exact
    area = float(np.pi / m * np.sum(x * dy - y * dx))
    # second moments about the centre (exact on the uniform grid)
    xc, yc = x - x.mean(), y - y.mean()
    cov = np.array([[np.mean(xc * xc), np.mean(xc * yc)], [np.mean(xc * yc), np.mean(yc * yc)]])
    lam = np.linalg.eigvalsh(cov)
    ellipticity = float(np.sqrt(max(lam[0], 0.0) / lam[1])) if lam[1] > 0 else float("nan")
    # tangent turning
    psi = np.arctan2(dy, dx)
    dpsi = np.diff(np.append(psi, psi[0]))
    dpsi = (dpsi + np.pi) % (2 * np.pi) - np.pi
    total = float(np.sum(dpsi))
    turning = int(np.round(total / (2 * np.pi)))
    s = np.sign(turning) if turning != 0 else (np.sign(whirl_hint) or 1.0)
    absturn = float(np.sum(np.abs(dpsi)))
    concavity = float(np.sum(np.maximum(0.0, -s * dpsi)) / absturn) if absturn > 0 else float("nan")
    # diameter: coarse pairwise search on every third grid point, then a fine local search
    z = (x + 1j * y)[::3]
    d2 = np.abs(z[:, None] - z[None, :])
    i, j = np.unravel_index(int(np.argmax(d2)), d2.shape)
    step = 3 * 2 * np.pi / m
    fine = np.linspace(-step, step, 65)
    xi, yi, _, _ = _eval(cx, cy, theta[3 * i] + fine)
    xj, yj, _, _ = _eval(cx, cy, theta[3 * j] + fine)
    zi, zj = xi + 1j * yi, xj + 1j * yj
    pp = float(max(np.max(np.abs(zi[:, None] - zj[None, :])), d2[i, j]))
    return OrbitShape(pp, area, ellipticity, turning, concavity, np.column_stack([x, y]))
