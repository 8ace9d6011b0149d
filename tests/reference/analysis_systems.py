"""Dynamical systems with independently known Lyapunov exponents / motion types.

Used by ``tests/test_analysis_*.py`` to check the generic LLE and motion-type code.

Known answers (literature / closed form):

* Lorenz σ=10, ρ=28, β=8/3: λ1 ≈ 0.9056 per time unit (Sprott, *Chaos and
  Time-Series Analysis*, 2003, Table; Viswanath 1998: 0.905 6).
* Damped linear oscillator x'' + 2ζω x' + ω² x = 0, ζ < 1: both exponents −ζω.
* Two uncoupled Stuart–Landau oscillators z' = (1 + iω_k + i b|z|²) z − |z|² z:
  attracting 2-torus |z_k| = 1, exponents (0, 0, −2, −2); sampled every 2π/ω_1
  the section is an invariant closed curve, LLE of that map 0.
* Logistic map r=4: λ = ln 2.  Hénon a=1.4, b=0.3: λ1 ≈ 0.419 22 per iteration.
* Sine circle map θ' = θ + Ω − K/(2π) sin 2πθ with K < 1 and Ω outside the
  Arnold tongues (golden mean): quasi-periodic, λ = 0.
"""
from __future__ import annotations

import numpy as np
from numba import njit
from scipy.integrate import solve_ivp
from scipy.linalg import expm

LORENZ_LLE = 0.9056
HENON_LLE = 0.41922
LOGISTIC_LLE = float(np.log(2.0))


# ---------------------------------------------------------------- Lorenz
@njit(cache=True)
def _lorenz_rhs(s, out):
    out[0] = 10.0 * (s[1] - s[0])
    out[1] = s[0] * (28.0 - s[2]) - s[1]
    out[2] = s[0] * s[1] - (8.0 / 3.0) * s[2]


@njit(cache=True)
def _lorenz_tangent_rhs(s, out):
    x, y, z = s[0], s[1], s[2]
    out[0] = 10.0 * (y - x)
    out[1] = x * (28.0 - z) - y
    out[2] = x * y - (8.0 / 3.0) * z
    vx, vy, vz = s[3], s[4], s[5]
    out[3] = 10.0 * (vy - vx)
    out[4] = (28.0 - z) * vx - vy - x * vz
    out[5] = y * vx + x * vy - (8.0 / 3.0) * vz


@njit(cache=True)
def _rk4_lorenz(s0, t, n_steps, tangent):
    s = s0.copy()
    h = t / n_steps
    k1 = np.empty_like(s)
    k2 = np.empty_like(s)
    k3 = np.empty_like(s)
    k4 = np.empty_like(s)
    for _ in range(n_steps):
        if tangent:
            _lorenz_tangent_rhs(s, k1)
            _lorenz_tangent_rhs(s + 0.5 * h * k1, k2)
            _lorenz_tangent_rhs(s + 0.5 * h * k2, k3)
            _lorenz_tangent_rhs(s + h * k3, k4)
        else:
            _lorenz_rhs(s, k1)
            _lorenz_rhs(s + 0.5 * h * k1, k2)
            _lorenz_rhs(s + 0.5 * h * k2, k3)
            _lorenz_rhs(s + h * k3, k4)
        s = s + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return s


def lorenz_flow(interval: float = 0.5, h: float = 0.005):
    """Flow map of the Lorenz system over ``interval`` time units (RK4, step h)."""
    n = int(round(interval / h))

    def flow(state: np.ndarray) -> np.ndarray:
        return _rk4_lorenz(np.asarray(state, dtype=float), interval, n, False)

    return flow


def lorenz_tangent(interval: float = 0.5, h: float = 0.005):
    """State + variational-equation map of the Lorenz system over ``interval``."""
    n = int(round(interval / h))

    def tangent(state: np.ndarray, vector: np.ndarray):
        s = _rk4_lorenz(np.concatenate([state, vector]).astype(float), interval, n, True)
        return s[:3], s[3:]

    return tangent


# ---------------------------------------------------------------- torus
@njit(cache=True)
def _torus_rhs(s, out, w1, w2, shear):
    for k in range(2):
        x = s[2 * k]
        y = s[2 * k + 1]
        r2 = x * x + y * y
        w = (w1 if k == 0 else w2) + shear * r2
        out[2 * k] = (1.0 - r2) * x - w * y
        out[2 * k + 1] = (1.0 - r2) * y + w * x


@njit(cache=True)
def _rk4_torus(s0, t, n_steps, w1, w2, shear):
    s = s0.copy()
    h = t / n_steps
    k1 = np.empty_like(s)
    k2 = np.empty_like(s)
    k3 = np.empty_like(s)
    k4 = np.empty_like(s)
    for _ in range(n_steps):
        _torus_rhs(s, k1, w1, w2, shear)
        _torus_rhs(s + 0.5 * h * k1, k2, w1, w2, shear)
        _torus_rhs(s + 0.5 * h * k2, k3, w1, w2, shear)
        _torus_rhs(s + h * k3, k4, w1, w2, shear)
        s = s + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return s


TORUS_W1 = 1.0
TORUS_W2 = float(np.sqrt(2.0))


def torus_flow(shear: float = 0.3, steps: int = 200):
    """Stroboscopic map (period 2π/ω1) of two Stuart–Landau oscillators: an attracting torus."""
    period = 2 * np.pi / TORUS_W1

    def flow(state: np.ndarray) -> np.ndarray:
        return _rk4_torus(np.asarray(state, dtype=float), period, steps, TORUS_W1, TORUS_W2, shear)

    return flow


# ---------------------------------------------------------------- damped oscillator
def damped_oscillator_matrix(omega_n: float, zeta: float) -> np.ndarray:
    return np.array([[0.0, 1.0], [-omega_n ** 2, -2 * zeta * omega_n]])


def damped_oscillator_flow_exact(omega_n: float, zeta: float, interval: float):
    """Exact flow map (matrix exponential)."""
    phi = expm(damped_oscillator_matrix(omega_n, zeta) * interval)
    return lambda s: phi @ s


def damped_oscillator_flow_adaptive(omega_n: float, zeta: float, interval: float, rtol: float = 1e-10):
    """Flow map through scipy's adaptive DOP853 (like the rotor's adaptive integrator)."""
    a = damped_oscillator_matrix(omega_n, zeta)

    def flow(s: np.ndarray) -> np.ndarray:
        sol = solve_ivp(lambda t, y: a @ y, (0.0, interval), s, method="DOP853", rtol=rtol, atol=1e-14)
        return sol.y[:, -1]

    return flow


# ---------------------------------------------------------------- maps
def logistic_map(r: float = 4.0):
    return lambda s: r * s * (1.0 - s)


def henon_map(a: float = 1.4, b: float = 0.3):
    return lambda s: np.array([1.0 - a * s[0] ** 2 + s[1], b * s[0]])


def henon_tangent(a: float = 1.4, b: float = 0.3):
    def tangent(s, v):
        jac = np.array([[-2 * a * s[0], 1.0], [b, 0.0]])
        return np.array([1.0 - a * s[0] ** 2 + s[1], b * s[0]]), jac @ v

    return tangent


def iterate(map_, x0, n: int, transient: int = 0) -> np.ndarray:
    """Iterate a map, drop the transient, return (n, ...) points."""
    x = np.asarray(x0, dtype=float)
    for _ in range(transient):
        x = map_(x)
    out = []
    for _ in range(n):
        x = map_(x)
        out.append(np.array(x, dtype=float))
    return np.array(out)


GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0


def circle_map_points(n: int, omega: float = GOLDEN, k: float = 0.5, transient: int = 500) -> np.ndarray:
    """Sine circle map, embedded in the plane as (cos 2πθ, sin 2πθ): shape (n, 2)."""
    theta = 0.1
    pts = []
    for i in range(transient + n):
        theta = (theta + omega - k / (2 * np.pi) * np.sin(2 * np.pi * theta)) % 1.0
        if i >= transient:
            pts.append((np.cos(2 * np.pi * theta), np.sin(2 * np.pi * theta)))
    return np.array(pts)


def forced_oscillator_flow(omega_n: float, zeta: float, interval: float, rtol: float = 1e-10):
    """x'' + 2ζω x' + ω² x = cos t over ``interval`` (a multiple of 2π) from t ≡ 0 (DOP853)."""
    a = damped_oscillator_matrix(omega_n, zeta)

    def flow(s: np.ndarray) -> np.ndarray:
        sol = solve_ivp(lambda t, y: a @ y + np.array([0.0, np.cos(t)]), (0.0, interval), s,
                        method="DOP853", rtol=rtol, atol=1e-14)
        return sol.y[:, -1]

    return flow
