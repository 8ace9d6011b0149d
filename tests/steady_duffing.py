"""The forced Duffing oscillator as an independent test system for shooting and continuation.

x'' + δx' + αx + βx³ = γ cos ωt, stroboscopic map over T = 2π/ω, integrated by SciPy's
DOP853 with the variational equations and the analytic Jacobian (nothing shared with the
rotor's compiled kernels).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.integrate import solve_ivp

from rotordiag.simulator.steady import MapEval


@dataclass(frozen=True)
class DuffingMap:
    delta: float
    alpha: float
    beta: float
    gamma: float
    omega: float
    rtol: float = 1e-11
    atol: float = 1e-12
    dim: int = 2

    def _rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        x, v = y[0], y[1]
        acc = -self.delta * v - self.alpha * x - self.beta * x**3 + self.gamma * math.cos(self.omega * t)
        out = [v, acc]
        if y.size > 2:
            phi = y[2:].reshape(2, 2)
            jac = np.array([[0.0, 1.0], [-self.alpha - 3 * self.beta * x * x, -self.delta]])
            out += list((jac @ phi).ravel())
        return np.array(out)

    def evaluate(self, x: np.ndarray, n_periods: int = 1, monodromy: bool = False) -> MapEval:
        period = 2 * math.pi / self.omega
        y0 = np.concatenate([x, np.eye(2).ravel()]) if monodromy else np.asarray(x, dtype=float)
        sol = solve_ivp(self._rhs, (0.0, n_periods * period), y0, method="DOP853", rtol=self.rtol, atol=self.atol,
                        t_eval=period * np.arange(1, n_periods + 1))
        ys = sol.y.T
        return MapEval(ys[-1, :2].copy(), ys[-1, 2:].reshape(2, 2).copy() if monodromy else None,
                       ys[:, :2].copy(), "ok" if sol.success else "diverged", int(sol.nfev))

    def difference(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.asarray(a) - np.asarray(b)


@dataclass(frozen=True)
class DuffingFamily:
    base: DuffingMap
    parameter: str = "omega"
    scale: float = 1.0

    def at(self, value: float) -> DuffingMap:
        return replace(self.base, **{self.parameter: float(value)})


def harmonic_balance_folds(delta: float, alpha: float, beta: float, gamma: float) -> tuple[float, float]:
    """ω of the two folds of the one-harmonic balance curve [(α − ω² + ¾βa²)² + (δω)²]a² = γ².

    On the curve W = ω² solves W² − (2c − δ²)W + c² − γ²/a² = 0 with c = α + ¾βa²; the folds
    are the interior extrema of ω(a) on the high-frequency root (β > 0). Returns (jump down, jump up).
    """
    a = np.linspace(1e-3, 10.0, 400_001)
    c = alpha + 0.75 * beta * a**2
    disc = (2 * c - delta**2) ** 2 - 4 * (c**2 - gamma**2 / a**2)
    ok = disc >= 0
    w_hi = np.full_like(a, np.nan)
    w_lo = np.full_like(a, np.nan)
    w_hi[ok] = np.sqrt(((2 * c - delta**2)[ok] + np.sqrt(disc[ok])) / 2)
    w_lo_sq = ((2 * c - delta**2)[ok] - np.sqrt(disc[ok])) / 2
    w_lo[ok] = np.where(w_lo_sq > 0, np.sqrt(np.maximum(w_lo_sq, 0)), np.nan)
    # along the high-frequency root, with a increasing from 0: ω falls from ∞ to a local minimum
    # (the jump up), rises to a local maximum (the jump down), then falls to the closing point
    w = w_hi[ok]
    turns = np.flatnonzero(np.diff(np.sign(np.diff(w))) != 0) + 1
    if len(turns) < 2:
        raise ValueError("no folds: the response curve does not bend over at these parameters")
    return float(w[turns[1]]), float(w[turns[0]])


@dataclass(frozen=True)
class NoisyDuffingMap:
    """A DuffingMap whose Pⁿ carries a deterministic error of size ``noise`` (a hash of the start
    state seeds it): a map whose residual cannot fall below the integrator's error, like the
    rotor's on a strongly unstable orbit. The monodromy matrix stays exact."""

    base: DuffingMap
    noise: float
    dim: int = 2

    def evaluate(self, x: np.ndarray, n_periods: int = 1, monodromy: bool = False) -> MapEval:
        ev = self.base.evaluate(x, n_periods, monodromy)
        seed = int.from_bytes(np.asarray(x, dtype=float).tobytes()[:16], "little") % (2**63) + n_periods
        err = self.noise * np.random.default_rng(seed).uniform(-1.0, 1.0, 2)
        sections = ev.sections.copy()
        sections[-1] += err
        return MapEval(ev.value + err, ev.monodromy, sections, ev.status, ev.nfev)

    def difference(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.asarray(a) - np.asarray(b)


@dataclass(frozen=True)
class NoisyDuffingFamily:
    base: DuffingMap
    noise: float
    parameter: str = "omega"
    scale: float = 1.0

    def at(self, value: float) -> NoisyDuffingMap:
        return NoisyDuffingMap(replace(self.base, **{self.parameter: float(value)}), self.noise)


@dataclass(frozen=True)
class IsolaMap:
    """P(x) = x + c·(x₁² + (p − p₀)² − r², x₂), c = −1/2: its fixed points are the circle
    x₁² + (p − p₀)² = r², x₂ = 0 — a closed branch (isola) with folds at p₀ ± r. The multipliers
    are 1 − x₁ and 1/2: the half x₁ > 0 is stable, x₁ < 0 unstable."""

    p: float
    p0: float = 1.0
    r: float = 0.5
    dim: int = 2

    def evaluate(self, x: np.ndarray, n_periods: int = 1, monodromy: bool = False) -> MapEval:
        y = np.asarray(x, dtype=float).copy()
        m = np.eye(2)
        secs = []
        for _ in range(n_periods):
            jac = np.array([[1.0 - y[0], 0.0], [0.0, 0.5]])
            y = y - 0.5 * np.array([y[0] ** 2 + (self.p - self.p0) ** 2 - self.r**2, y[1]])
            m = jac @ m
            secs.append(y.copy())
        return MapEval(y, m if monodromy else None, np.array(secs), "ok", n_periods)

    def difference(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.asarray(a) - np.asarray(b)


@dataclass(frozen=True)
class IsolaFamily:
    parameter: str = "p"
    scale: float = 1.0

    def at(self, value: float) -> IsolaMap:
        return IsolaMap(float(value))
