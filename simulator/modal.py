"""Linearised (modal) analysis about the static equilibrium (MODEL.md section 7).

The modal model is the aligned rotor (Δ = 0, A = 0) with the mean generator
stiffness (ρ → 0, the paper's "linearized model"). It is then autonomous, so
the static equilibrium is a fixed point of the right-hand side and the state
matrix is its Jacobian there; the bearings enter through their linearised
stiffness and damping (also reported by :func:`bearing_coefficients`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from . import _kernels as K
from .params import Plant
from .system import RotorSystem

# Aligned system: the 10 position coordinates [X1, Y1, X2, Y2, X4, Y4, X5, Y5, X6, Y6]
_Q = np.arange(10)
_V = np.arange(11, 21)
_STATE = np.concatenate([_Q, _V])
_FD_STEP = 1e-7
_NODE_OF_Q = (1, 2, 4, 5, 6)  # node numbers of coordinate pairs 0..4


@dataclass(frozen=True)
class ModalResult:
    """Modes of the linearised rotor.

    Attributes
    ----------
    frequencies_hz : ndarray, shape (n_modes,)
        Damped natural frequencies of the oscillatory modes, ascending.
    damping_ratios : ndarray, shape (n_modes,)
        ζ = −Re λ / |λ| (negative = unstable).
    mode_shapes : ndarray, shape (n_modes, 6, 2), complex
        Displacements of nodes 1..6 (x, y), normalised to unit largest magnitude.
    eigenvalues_per_s : ndarray, shape (20,), complex
        All eigenvalues of the state matrix, rad/s.
    stability_margin_per_s : float
        Largest real part of the eigenvalues (> 0 = linearly unstable), 1/s.
    equilibrium_m : ndarray, shape (6, 2)
        Static equilibrium positions of nodes 1..6, metres.
    speed_rpm : float
    """

    frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    mode_shapes: np.ndarray
    eigenvalues_per_s: np.ndarray
    stability_margin_per_s: float
    equilibrium_m: np.ndarray
    speed_rpm: float

    @property
    def stable(self) -> bool:
        return self.stability_margin_per_s < 0.0


def _linear_system(plant: Plant, speed_rpm: float) -> RotorSystem:
    return RotorSystem(plant.replace(asymmetry=0.0), speed_rpm, 0.0, 0.0, mechanism="aligned")


def _solve_equilibrium(system: RotorSystem, guess: np.ndarray) -> tuple[np.ndarray, bool]:
    y = np.zeros(K.N_STATE)

    def residual(q: np.ndarray) -> np.ndarray:
        y[_Q] = q
        acc = system.rhs(0.0, y)[_V]
        return np.where(np.isfinite(acc), acc, 1e6)

    sol = optimize.root(residual, guess, method="hybr", options={"xtol": 1e-13})
    ok = bool(sol.success) and np.max(np.abs(residual(sol.x))) < 1e-9
    return sol.x, ok


def static_equilibrium(plant: Plant, speed_rpm: float) -> np.ndarray:
    """Static equilibrium state (22,) of the aligned, mean-stiffness rotor at ``speed_rpm``.

    Newton (MINPACK hybrid) from the MODEL.md start; if that fails, continuation
    downward from 6000 r/min, where the bearings are stiff and eccentricities small.
    """
    system = _linear_system(plant, speed_rpm)
    q0 = system.initial_state()[_Q]
    q, ok = _solve_equilibrium(system, q0)
    if not ok:
        speeds = np.geomspace(6000.0, speed_rpm, 40)
        q = np.array([0.0, -0.05, 0.0, -0.05 - q0[1] + q0[3], 0.0, -0.05, 0.0, -0.05 - q0[5] + q0[7], 0.0, -0.05])
        for s in speeds:
            q, ok = _solve_equilibrium(_linear_system(plant, float(s)), q)
            if not ok:
                break
    if not ok:
        raise ValueError(f"no static equilibrium found at {speed_rpm} r/min (bearings overloaded?)")
    y = np.zeros(K.N_STATE)
    y[_Q] = q
    return y


def _jacobian(system: RotorSystem, y: np.ndarray) -> np.ndarray:
    n = len(_STATE)
    J = np.empty((n, n))
    for j, idx in enumerate(_STATE):
        yp = y.copy()
        ym = y.copy()
        yp[idx] += _FD_STEP
        ym[idx] -= _FD_STEP
        J[:, j] = (system.rhs(0.0, yp)[_STATE] - system.rhs(0.0, ym)[_STATE]) / (2 * _FD_STEP)
    return J


def state_matrix(plant: Plant, speed_rpm: float) -> tuple[np.ndarray, np.ndarray]:
    """State matrix (20×20, per second) of the linearised rotor, and the equilibrium state."""
    system = _linear_system(plant, speed_rpm)
    y = static_equilibrium(plant, speed_rpm)
    return _jacobian(system, y) * system.speed_rad_s, y


def modal(plant: Plant, speed_rpm: float) -> ModalResult:
    """Natural frequencies, damping ratios and mode shapes at ``speed_rpm``.

    Parameters
    ----------
    plant : Plant
    speed_rpm : float
        Running speed, r/min (100–6000); the bearing coefficients depend on it.

    Returns
    -------
    ModalResult
    """
    system = _linear_system(plant, speed_rpm)
    A, y = state_matrix(plant, speed_rpm)
    lam, vec = np.linalg.eig(A)
    osc = lam.imag > 1e-6 * np.abs(lam).max()
    order = np.argsort(lam.imag[osc])
    lam_o = lam[osc][order]
    vec_o = vec[:, osc][:, order]
    shapes = np.zeros((len(lam_o), 6, 2), dtype=complex)
    for i in range(len(lam_o)):
        q = vec_o[:10, i].reshape(5, 2)
        for k, node in enumerate(_NODE_OF_Q):
            shapes[i, node - 1] = q[k]
        shapes[i, 2] = shapes[i, 3]  # node 3 = node 4 (aligned)
        shapes[i] /= shapes[i].flat[np.argmax(np.abs(shapes[i]))]
    return ModalResult(
        frequencies_hz=lam_o.imag / (2 * np.pi),
        damping_ratios=-lam_o.real / np.abs(lam_o),
        mode_shapes=shapes,
        eigenvalues_per_s=lam,
        stability_margin_per_s=float(lam.real.max()),
        equilibrium_m=system.node_positions(np.zeros(1), y)[0],
        speed_rpm=float(speed_rpm),
    )


def bearing_coefficients(plant: Plant, speed_rpm: float) -> tuple[np.ndarray, np.ndarray]:
    """Linearised oil-film stiffness and damping of bearings 1..4 at the static equilibrium.

    Returns
    -------
    stiffness_n_m : ndarray, shape (4, 2, 2)
        k_ij = −∂F_i/∂x_j (N/m), i, j ∈ {x, y}.
    damping_n_s_m : ndarray, shape (4, 2, 2)
        c_ij = −∂F_i/∂ẋ_j (N·s/m).
    """
    system = _linear_system(plant, speed_rpm)
    y = static_equilibrium(plant, speed_rpm)
    w = system.speed_rad_s
    c = plant.clearance_m
    p = system.params
    pos = {0: (0, 1, 11, 12), 1: (4, 5, 15, 16), 2: (4, 5, 15, 16), 3: (8, 9, 19, 20)}
    kmat = np.empty((4, 2, 2))
    cmat = np.empty((4, 2, 2))
    for b in range(4):
        ix, iy, ivx, ivy = pos[b]
        base = np.array([y[ix], y[iy], y[ivx], y[ivy]])

        def force(v: np.ndarray) -> np.ndarray:
            return np.array(K.bearing_force(p, b, v[0], v[1], v[2], v[3])) * c * w**2  # N

        J = np.empty((2, 4))
        for j in range(4):
            d = np.zeros(4)
            d[j] = _FD_STEP
            J[:, j] = (force(base + d) - force(base - d)) / (2 * _FD_STEP)
        kmat[b] = -J[:, :2] / c
        cmat[b] = -J[:, 2:] / (c * w)
    return kmat, cmat
