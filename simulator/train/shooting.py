"""Shooting on the train: its once-per-revolution map in the ``simulator.steady`` flow-map interface.

:class:`TrainMap` advances a reduced state of the train by whole revolutions from t ≡ 0 (mod T) with the
fixed-step exponential integrator of :mod:`.dynamics` (deterministic in the start state, so the map is a
smooth function of it), and gives its monodromy matrix by central differences. It satisfies
``simulator.steady.PeriodicMap``, so ``steady.find_fixed_point`` finds the train's period-n orbits and their
Floquet multipliers. Meant for operation where the static linearisation holds (the ETD's step was checked
there); beyond the linear stability threshold use the time response (:func:`.dynamics.simulate_train`).
"""
from __future__ import annotations

import math

import numpy as np

from ..steady import FixedPoint, MapEval, find_fixed_point
from .dynamics import Kernel, _integrate_etd, build_kernel, etd_matrices, initial_state
from .fe import Assembly, assemble
from .model import Train, TrainError

__all__ = ["TrainMap", "TrainSpeedFamily", "train_fixed_point"]


class TrainMap:
    """Stroboscopic map of the reduced train at ``kernel``'s speed: ``steps_per_rev`` ETDRK4 steps per
    revolution; ``fd_rel`` scales the difference steps of the monodromy matrix (relative to the state's
    position and velocity magnitudes)."""

    def __init__(self, kernel: Kernel, speed_rpm: float, steps_per_rev: int = 64, fd_rel: float = 1e-6):
        if steps_per_rev < 4:
            raise TrainError("steps_per_rev must be ≥ 4")
        self.kernel = kernel
        self.speed_rpm = float(speed_rpm)
        self.steps_per_rev = int(steps_per_rev)
        self.fd_rel = float(fd_rel)
        self.dim = 2 * kernel.red.n
        self._h = 2 * math.pi / kernel.speed_rad_s / self.steps_per_rev
        initial_state(kernel, speed_rpm)  # the static state: ETD's linearisation point
        self._mats = etd_matrices(kernel, self._h)

    def _advance(self, x: np.ndarray, n_periods: int) -> tuple[int, np.ndarray]:
        k = self.kernel
        grid = np.full((n_periods, self.dim), np.nan)
        status, _, _ = _integrate_etd(np.ascontiguousarray(x, dtype=float), self._h, n_periods * self.steps_per_rev,
                                      self.steps_per_rev, self.steps_per_rev, grid, k.red.n, *self._mats,
                                      k.args[1:], k.args[10], k.args[11], k.clear, k.args[12])
        return int(status), grid

    def evaluate(self, x: np.ndarray, n_periods: int, monodromy: bool = False) -> MapEval:
        status, sections = self._advance(x, n_periods)
        names = ("ok", "contact", "diverged")
        nfev = 4 * n_periods * self.steps_per_rev
        mono = None
        if monodromy and status == 0:
            n = self.kernel.red.n
            scale = np.concatenate([np.full(n, max(np.abs(x[:n]).max(), 1e-9)),
                                    np.full(n, max(np.abs(x[n:]).max(), 1e-9 * self.kernel.speed_rad_s))])
            mono = np.empty((self.dim, self.dim))
            for j in range(self.dim):
                d = self.fd_rel * scale[j]
                xp = x.copy()
                xm = x.copy()
                xp[j] += d
                xm[j] -= d
                sp, gp = self._advance(xp, n_periods)
                sm, gm = self._advance(xm, n_periods)
                if sp or sm:
                    return MapEval(sections[-1], None, sections, names[max(sp, sm)], nfev)
                mono[:, j] = (gp[-1] - gm[-1]) / (2 * d)
            nfev *= 1 + 2 * self.dim
        return MapEval(sections[-1].copy(), mono, sections, names[status], nfev)

    def difference(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.asarray(a) - np.asarray(b)


def train_fixed_point(kernel: Kernel, speed_rpm: float, n_periods: int = 1, *, steps_per_rev: int = 64,
                      tol_m: float = 1e-13, x0: np.ndarray | None = None) -> FixedPoint:
    """The train's period-``n_periods`` orbit by Newton shooting from ``x0`` (default: the static state);
    ``tol_m`` bounds max |Pⁿ(x) − x| over the reduced coordinates and velocities."""
    pmap = TrainMap(kernel, speed_rpm, steps_per_rev)
    start = initial_state(kernel, speed_rpm) if x0 is None else np.asarray(x0, dtype=float)
    return find_fixed_point(pmap, start, n_periods, tol=tol_m)


class TrainSpeedFamily:
    """The train's maps over running speed, for ``steady.continuation.continue_branch`` (parameter
    ``speed_rpm``, scaled by ``scale_rpm``); a kernel (reduction, static state, ETD matrices) per speed,
    kept for the last ``cache`` speeds."""

    parameter = "speed_rpm"

    def __init__(self, train: Train | Assembly, *, n_modes: int = 12, steps_per_rev: int = 64,
                 scale_rpm: float = 1000.0, cache: int = 8):
        self.assembly = train if isinstance(train, Assembly) else assemble(train)
        self.n_modes = int(n_modes)
        self.steps_per_rev = int(steps_per_rev)
        self.scale = float(scale_rpm)
        self._cache: dict[float, TrainMap] = {}
        self._keep = int(cache)

    def at(self, value: float) -> TrainMap:
        speed = float(value)
        if not (math.isfinite(speed) and speed > 0):
            raise TrainError(f"speed_rpm must be positive (got {speed!r})")
        if speed not in self._cache:
            if len(self._cache) >= self._keep:
                self._cache.pop(next(iter(self._cache)))
            kern = build_kernel(self.assembly, speed, self.n_modes)
            self._cache[speed] = TrainMap(kern, speed, self.steps_per_rev)
        return self._cache[speed]
