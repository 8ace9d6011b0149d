"""The rotor's once-per-revolution (Poincaré) map and its derivative, on the dynamic state.

:class:`RotorMap` wraps a :class:`~rotordiag.simulator.RotorSystem`: it advances a
state by whole revolutions from τ ≡ 0 (mod 2π) — the equations are 2π-periodic in
τ = Ωt, so this is the stroboscopic Poincaré map P — and, on request, returns the
monodromy matrix ∂Pⁿ/∂x from the variational equations integrated alongside
(:mod:`._variational`).

Only the *dynamic* components enter (``x``, the reduced state): for ``aligned``,
``rigid``, ``offset`` and ``flexible`` the coupling angle φ and φ' are not
dynamic (constant, or φ = τ + φ0) and are left out, as in the Lyapunov runs; a
perturbation there would never decay and fake a multiplier of 1. For ``pin`` φ
is dynamic but an angle: differences of φ are taken modulo 2π, so an orbit on
which the coupling link turns k whole times per period is still a fixed point.

Every call starts the integrator with the same first step, so Pⁿ is a
deterministic function of the start state (``RotorSystem.integrate`` reuses the
last step size between calls, which is right for a long run and wrong here).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from rotordiag.core.numerics import MAX_STEPS_PER_REV

from .. import _kernels as K
from ..system import TWO_PI, RotorSystem
from ._variational import integrate_variational

__all__ = ["MapEval", "PeriodicMap", "RotorMap", "STATUS_NAMES", "inactive_components"]

STATUS_NAMES = {K.STATUS_OK: "ok", K.STATUS_CONTACT: "contact", K.STATUS_DIVERGED: "diverged"}
#: First trial step of every map evaluation (τ units): the map must not depend on the previous call.
FIRST_STEP = TWO_PI / 200.0


@dataclass
class MapEval:
    """One evaluation of Pⁿ at a reduced state.

    Attributes
    ----------
    value : ndarray, shape (m,)
        Pⁿ(x).
    monodromy : ndarray, shape (m, m) or None
        ∂Pⁿ/∂x (None when not asked for).
    sections : ndarray, shape (n, m)
        P(x), P²(x), …, Pⁿ(x).
    status : {"ok", "contact", "diverged"}
    nfev : int
        Right-hand-side evaluations (base trajectory and directional differences).
    """

    value: np.ndarray
    monodromy: np.ndarray | None
    sections: np.ndarray
    status: str
    nfev: int

    @property
    def ok(self) -> bool:
        return self.status == "ok"


class PeriodicMap(Protocol):
    """What shooting and continuation need of a stroboscopic map (the rotor's, or a test system's)."""

    dim: int

    def evaluate(self, x: np.ndarray, n_periods: int, monodromy: bool = False) -> MapEval: ...

    def difference(self, a: np.ndarray, b: np.ndarray) -> np.ndarray: ...


def inactive_components(mechanism: str) -> tuple[int, ...]:
    """State components that are not dynamic for a mechanism (φ, φ' unless ``pin``)."""
    return () if mechanism == "pin" else (10, 21)


class RotorMap:
    """Pⁿ of a :class:`RotorSystem` on its dynamic state components.

    Parameters
    ----------
    system : RotorSystem
        The rotor at one operating point (its ``rtol``/``atol`` are the map's).
    central : bool
        Central instead of forward directional differences for J·v in the
        variational equations (twice the cost; ~1e-10 instead of ~1e-8 relative).
    """

    def __init__(self, system: RotorSystem, *, central: bool = False) -> None:
        self.system = system
        self.central = bool(central)
        self.template = system.initial_state()  # values of the inactive components
        inactive = inactive_components(system.mechanism)
        self.active = np.array([i for i in range(system.n_state) if i not in inactive], dtype=np.int64)
        self.dim = int(self.active.size)
        #: position of φ in the reduced state (``pin``), else -1
        self.angle_index = int(np.flatnonzero(self.active == 10)[0]) if system.mechanism == "pin" else -1

    # ------------------------------------------------------------ state conversions
    def full(self, x: np.ndarray) -> np.ndarray:
        """Full state (n_state,) at τ ≡ 0 from a reduced one."""
        y = self.template.copy()
        y[self.active] = x
        return y

    def reduce(self, state: np.ndarray) -> np.ndarray:
        """Reduced (dynamic) components of a full state."""
        return np.asarray(state, dtype=float)[self.active].copy()

    def difference(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """a − b, with the coupling angle's difference taken into (−π, π]."""
        d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
        if self.angle_index >= 0:
            d[..., self.angle_index] = np.remainder(d[..., self.angle_index] + math.pi, TWO_PI) - math.pi
        return d

    # ------------------------------------------------------------ the map
    def evaluate(self, x: np.ndarray, n_periods: int = 1, monodromy: bool = False,
                 rtol: float | None = None) -> MapEval:
        """Pⁿ(x) (and ∂Pⁿ/∂x with ``monodromy=True``), n = ``n_periods`` revolutions from τ = 0.

        ``rtol`` (optional) integrates this evaluation at another relative tolerance (atol
        scaled with it): a loose one gives a cheap approximate monodromy matrix for chord
        iterations (rtol 1e-3: M to ~3e-4 relative at a quarter of the cost). The map itself
        is then the looser integrator's, so its ``value`` is not the system's Pⁿ.
        """
        n = int(n_periods)
        if n < 1:
            raise ValueError(f"n_periods must be an integer >= 1, got {n_periods!r}")
        y0 = self.full(np.asarray(x, dtype=float))
        nfull = y0.size
        if monodromy:
            phi0 = np.zeros((nfull, self.dim))
            phi0[self.active, np.arange(self.dim)] = 1.0
        else:
            phi0 = np.zeros((nfull, 0))
        pcs = np.full((n, nfull), np.nan)
        sysm = self.system
        rt, at = (sysm.rtol, sysm.atol) if rtol is None else (float(rtol), sysm.atol * float(rtol) / sysm.rtol)
        status, _, y, phi, nfev, _, _, _ = integrate_variational(
            y0, phi0, 0.0, TWO_PI * n, sysm.params, rt, at, FIRST_STEP,
            int(MAX_STEPS_PER_REV * n) + 1000, self.central, pcs)
        status_name = STATUS_NAMES[int(status)]
        if status_name == "ok":
            pcs[-1] = y
        return MapEval(
            value=y[self.active].copy(),
            monodromy=phi[self.active].copy() if monodromy else None,
            sections=pcs[:, self.active].copy(),
            status=status_name,
            nfev=int(nfev),
        )
