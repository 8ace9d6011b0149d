"""The linearised train: bearing coefficients at the static state, modes, Campbell diagram,
critical speeds and the steady unbalance response (the asymmetry at its mean).

Bearing stiffness and damping are taken by central differences of each bearing's ``force_n`` about its
static journal position (K = −∂f/∂x, C = −∂f/∂v), so any bearing model serves and no sign convention
of a coefficient table is assumed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from .fe import Assembly, assemble
from .model import Train
from .reduced import Reduced
from .static import StaticState, static_state


def bearing_coefficients(brg, x_m: float, y_m: float, speed_rad_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(K, C), 2×2 each, of one bearing about (x, y) at rest: f ≈ f0 − K dx − C v."""
    c = float(brg.clearance_m)
    h = 1e-6 * c
    hv = 1e-6 * c * max(speed_rad_s, 1.0)
    K = np.empty((2, 2))
    C = np.empty((2, 2))
    for k in range(2):
        e = np.zeros(2)
        e[k] = 1.0
        fp = np.array(brg.force_n(x_m + h * e[0], y_m + h * e[1], 0.0, 0.0, speed_rad_s))
        fm = np.array(brg.force_n(x_m - h * e[0], y_m - h * e[1], 0.0, 0.0, speed_rad_s))
        K[:, k] = -(fp - fm) / (2 * h)
        fp = np.array(brg.force_n(x_m, y_m, hv * e[0], hv * e[1], speed_rad_s))
        fm = np.array(brg.force_n(x_m, y_m, -hv * e[0], -hv * e[1], speed_rad_s))
        C[:, k] = -(fp - fm) / (2 * hv)
    return K, C


def linear_matrices(asm: Assembly, speed_rad_s: float, journal_m: np.ndarray | None = None,
                    coefficients=bearing_coefficients) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """M, C, K of the train linearised at spin ``speed_rad_s`` about journals at ``journal_m`` (relative
    to their bearing centres; zero if not given), the asymmetric stiffness at its mean. ``coefficients``
    (brg, x, y, Ω) → (K, C) gives each bearing's (default: the force's own derivatives)."""
    eta = asm.train.internal_damping_s
    K = asm.mean_stiffness(speed_rad_s, eta)
    C = asm.damping(speed_rad_s, eta)
    for b, node in enumerate(asm.support_nodes):
        x, y = (0.0, 0.0) if journal_m is None else journal_m[b]
        kb, cb = coefficients(asm.bearings[b], float(x), float(y), speed_rad_s)
        s = slice(4 * node, 4 * node + 2)
        K[s, s] += kb
        C[s, s] += cb
    return asm.M, C, K


@dataclass
class Modes:
    """Damped modes at one speed, sorted by natural frequency (only ω > 0 roots)."""

    speed_rpm: float
    eigenvalues: np.ndarray
    frequency_hz: np.ndarray
    log_decrement: np.ndarray
    forward: np.ndarray
    shapes: np.ndarray

    @property
    def damping_ratio(self) -> np.ndarray:
        return -self.eigenvalues.real / np.abs(self.eigenvalues)


def modes(train: Train | Assembly, speed_rpm: float, static: StaticState | None = None,
          n_modes: int | None = None, *, about_static: bool = True, coefficients=bearing_coefficients) -> Modes:
    """Damped eigenvalues and mode shapes of the train linearised at ``speed_rpm``.

    ``about_static`` (default) linearises the bearings about the static state (solved here unless
    given); False linearises about the bearing centres (linear bearings do not care).
    """
    asm = train if isinstance(train, Assembly) else assemble(train)
    speed = speed_rpm * math.pi / 30.0
    journal = None
    if about_static:
        st = static if static is not None else static_state(asm, speed_rpm)
        journal = st.journal_m
    M, C, K = linear_matrices(asm, speed, journal, coefficients)
    n = M.shape[0]
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    Minv = np.linalg.inv(M)
    A[n:, :n] = -Minv @ K
    A[n:, n:] = -Minv @ C
    lam, vec = sla.eig(A)
    keep = lam.imag > 1e-6
    lam, vec = lam[keep], vec[:n, keep]
    order = np.argsort(lam.imag)
    lam, vec = lam[order], vec[:, order]
    if n_modes is not None:
        lam, vec = lam[:n_modes], vec[:, :n_modes]
    wd = lam.imag
    logdec = -2 * math.pi * lam.real / wd
    fwd = np.empty(len(lam), dtype=bool)
    for k in range(len(lam)):
        X, Y = vec[0::4, k], vec[1::4, k]
        fwd[k] = np.sum(np.abs(X + 1j * Y) ** 2) >= np.sum(np.abs(X - 1j * Y) ** 2)
    return Modes(speed_rpm=float(speed_rpm), eigenvalues=lam, frequency_hz=wd / (2 * math.pi),
                 log_decrement=logdec, forward=fwd, shapes=vec)


def campbell(train: Train | Assembly, speeds_rpm, n_modes: int = 8, *, about_static: bool = False) -> np.ndarray:
    """Damped natural frequencies (Hz), shape (len(speeds_rpm), n_modes)."""
    asm = train if isinstance(train, Assembly) else assemble(train)
    return np.array([modes(asm, s, n_modes=n_modes, about_static=about_static).frequency_hz for s in speeds_rpm])


def unbalance_response(train: Train | Assembly, speeds_rpm, *, about_static: bool = False,
                       static_by_speed=None) -> np.ndarray:
    """Steady 1X response to the train's unbalances: complex amplitudes (len(speeds), n_nodes, 2) of x and
    y, with x(t) = Re(X e^{iΩt}) (m, 0-pk), the asymmetric stiffness at its mean."""
    asm = train if isinstance(train, Assembly) else assemble(train)
    out = np.zeros((len(speeds_rpm), asm.n_nodes, 2), dtype=complex)
    for k, s in enumerate(speeds_rpm):
        w = s * math.pi / 30.0
        journal = None
        if about_static:
            st = static_by_speed(s) if static_by_speed is not None else static_state(asm, s)
            journal = st.journal_m
        M, C, K = linear_matrices(asm, w, journal)
        F = np.zeros(asm.n_dof, dtype=complex)
        for node, me, a in zip(asm.unbalance_nodes, asm.unbalance_kg_m, asm.unbalance_angle_rad, strict=True):
            F[4 * node] += me * w**2 * np.exp(1j * a)
            F[4 * node + 1] += -1j * me * w**2 * np.exp(1j * a)
        Q = np.linalg.solve(K - w**2 * M + 1j * w * C, F)
        out[k, :, 0] = Q[0::4]
        out[k, :, 1] = Q[1::4]
    return out


def critical_speeds(train: Train | Assembly, n: int, max_rpm: float, *, n_grid: int = 80,
                    about_static: bool = False) -> np.ndarray:
    """Speeds (r/min) where a forward or backward damped natural frequency equals the running speed (1X),
    the lowest ``n`` below ``max_rpm``, from the Campbell diagram by bracketing and Brent's method."""
    asm = train if isinstance(train, Assembly) else assemble(train)
    n_track = 2 * n + 4
    grid = np.linspace(max_rpm / n_grid, max_rpm, n_grid)
    return _one_x_crossings(lambda s: modes(asm, s, n_modes=n_track, about_static=about_static).frequency_hz,
                            campbell(asm, grid, n_track, about_static=about_static), grid, n_track)[:n]


def reduced_critical_speeds(red: Reduced, n: int, max_rpm: float, *, n_grid: int = 80,
                            n_track: int = 16) -> np.ndarray:
    """The critical speeds (r/min) of the reduced model ``red``: the full model's linear matrices (journals
    centred) projected on its basis, then the 1X crossings as :func:`critical_speeds` finds them; what the
    reduction's accuracy is judged by."""
    asm = red.assembly

    def freqs_hz(speed_rpm: float) -> np.ndarray:
        M, C, K = linear_matrices(asm, speed_rpm * math.pi / 30.0)
        Mr, Cr, Kr = (red.T.T @ A @ red.T for A in (M, C, K))
        m = Mr.shape[0]
        A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.linalg.solve(Mr, Kr), -np.linalg.solve(Mr, Cr)]])
        lam = np.linalg.eigvals(A)
        return np.sort(lam.imag[lam.imag > 1e-6]) / (2 * math.pi)

    grid = np.linspace(max_rpm / n_grid, max_rpm, n_grid)
    table = np.array([freqs_hz(s)[:n_track] for s in grid])
    return _one_x_crossings(freqs_hz, table, grid, n_track)[:n]


def _one_x_crossings(freqs_hz, table: np.ndarray, grid: np.ndarray, n_track: int) -> np.ndarray:
    """Speeds where branch k of ``freqs_hz(speed_rpm)`` (tabulated on ``grid`` in ``table``) crosses 1X, by
    bracketing on the grid and Brent's method, sorted."""
    from scipy.optimize import brentq

    found = []
    for k in range(n_track):
        g = table[:, k] - grid / 60.0
        for j in range(len(grid) - 1):
            if g[j] > 0 >= g[j + 1]:
                found.append(brentq(lambda s, k=k: freqs_hz(s)[k] - s / 60.0, grid[j], grid[j + 1], xtol=1e-6))
    return np.sort(np.array(found))
