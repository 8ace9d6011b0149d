"""Run-ups and coast-downs of a finite-element shaft train (issue 46).

:class:`TrainTransientModel` puts a :class:`~rotordiag.simulator.train.Train` behind
:class:`rotordiag.simulator.transient.VariableSpeedModel`, so :func:`~rotordiag.simulator.transient.simulate_transient`
runs it through a :class:`~rotordiag.simulator.transient.SpeedProfile` exactly as it runs the paper's model:
revolution by revolution at the revolution's mean speed. The train's state is dimensional (reduced
coordinates in m, their rates in m/s), so nothing is rescaled between revolutions; the speed enters through
the gyroscopic and internal-damping matrices, the film forces, the unbalance forces (m·e·Ω²) and the
coupling's 2X forcing, all rebuilt at each revolution's speed (``dynamics.build_kernel``, the modal basis
built once). Each revolution is integrated with the train's adaptive Dormand–Prince integrator
(``dynamics._integrate``): the fixed-step ETD one needs matrix exponentials per speed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from rotordiag.core.numerics import DEFAULT_RTOL, MAX_STEPS_PER_REV

from .dynamics import _A, _C, _D, _E, STATUS, Kernel, _integrate, build_kernel, initial_state
from .fe import assemble
from .model import Train, TrainError, Unbalance
from .reduced import reduce

__all__ = ["TrainTransientModel", "train_channels", "unbalanced"]

TWO_PI = 2.0 * math.pi


@dataclass
class _Step:
    """What :func:`simulate_transient` reads of an integration's end: its status and the τ it reached."""

    status: str
    tau: float


class _TrainAtSpeed:
    """The train at one speed as a flow map in τ = Ωt (the interface of ``RotorSystem.integrate``)."""

    def __init__(self, kernel: Kernel, speed_rpm: float, rtol: float, atol_m: float) -> None:
        self.kernel = kernel
        self.speed_rpm = float(speed_rpm)
        self.speed_rad_s = kernel.speed_rad_s
        self.rtol = rtol
        self.atol_m = atol_m

    def initial_state(self) -> np.ndarray:
        """The train at rest on its static state at this speed (zero velocities)."""
        return initial_state(self.kernel, self.speed_rpm)

    def integrate(self, y: np.ndarray, tau0: float, tau1: float, *, grid_t0: float = 0.0, grid_dt: float = 1.0,
                  n_grid: int = 0) -> tuple:
        """Integrate from τ0 to τ1 (τ0 a whole number of revolutions: the forcing's angle is τ − τ0 mod 2π);
        grid rows at τ = grid_t0 + k·grid_dt. Returns (state, grid, None, step, rows filled, None)."""
        w = self.speed_rad_s
        t_end = (tau1 - tau0) / w
        grid = np.full((max(int(n_grid), 0), y.shape[0]), np.nan)
        revs = max(1, math.ceil((tau1 - tau0) / TWO_PI))
        status, t, s, _, _, _, ng = _integrate(
            np.ascontiguousarray(y, dtype=float), t_end, t_end / (200 * revs), self.rtol, self.atol_m,
            grid_dt / w, (grid_t0 - tau0) / w, grid, MAX_STEPS_PER_REV * revs, *self.kernel.args,
            self.kernel.clear, _A, _C, _E, _D)
        return s, grid, None, _Step(STATUS[status], tau0 + t * w), int(ng), None


class TrainTransientModel:
    """A shaft train as a :class:`rotordiag.simulator.transient.VariableSpeedModel`.

    Parameters
    ----------
    train : Train
        Misalignment, unbalance and bearings as built (``misaligned``, ``bearing_moved``).
    n_modes : int
        Modes kept per rotor in the reduction (as :func:`simulate_train`).
    rtol, atol_m : float
        Dormand–Prince tolerances (``atol_m`` on every reduced coordinate and velocity).

    ``journal_displacements_m`` gives (n, n_bearings, 2): every journal relative to its housing, DC kept.
    """

    def __init__(self, train: Train, *, n_modes: int = 12, rtol: float = DEFAULT_RTOL,
                 atol_m: float = 1e-10) -> None:
        if not isinstance(train, Train):
            raise TrainError(f"train must be a Train, got {type(train).__name__}")
        self.train = train
        self.reduced = reduce(assemble(train), n_modes)
        self.n_modes = int(n_modes)
        self.rtol = float(rtol)
        self.atol_m = float(atol_m)
        asm = self.reduced.assembly
        self.clearances_m = np.array([float(b.clearance_m) for b in asm.bearings])
        self.clearance_m = float(self.clearances_m.min())
        self.n_bearings = len(asm.bearings)
        self.n_state = 2 * self.reduced.n
        self.bearing_names = [s.name or f"B{k + 1}" for k, (_, s) in enumerate(train.supports())]

    def describe(self) -> dict:
        """What a run's ``inputs`` record of the train: rotors, bearings and their centres, unbalances, reduction."""
        return {"kind": "shaft train", "rotors": [r.name for r in self.train.rotors], "bearings": self.bearing_names,
                "bearing_centres_m": self.reduced.assembly.support_centres_m.tolist(),
                "clearances_m": self.clearances_m.tolist(),
                "unbalances": [{"rotor": r.name, "station": u.station, "amount_kg_m": u.amount_kg_m,
                                "angle_rad": u.angle_rad} for r in self.train.rotors for u in r.unbalances],
                "n_modes": self.n_modes, "rtol": self.rtol, "atol_m": self.atol_m}

    def at_speed(self, speed_rpm: float) -> _TrainAtSpeed:
        return _TrainAtSpeed(build_kernel(self.reduced, speed_rpm), speed_rpm, self.rtol, self.atol_m)

    def velocity_indices(self) -> np.ndarray:
        return np.zeros(0, dtype=int)  # rates in m/s: continuous through a change of speed as they are

    def journal_displacements_m(self, system: _TrainAtSpeed, tau: np.ndarray, states: np.ndarray) -> np.ndarray:
        red = self.reduced
        return np.stack([states[:, j: j + 2] for j in red.support_index], axis=1) - \
            red.assembly.support_centres_m[None]


def train_channels(n_bearings: int) -> tuple[tuple[int, float], ...]:
    """The probe layout of a train's run-up: an x/y pair at 45° and 135° at every bearing, 1-based."""
    return tuple((b, a) for b in range(1, n_bearings + 1) for a in (45.0, 135.0))


def unbalanced(train: Train, amount_kg_m: float, *, rotor: int = 0, station: int | None = None,
               angle_rad: float = 0.0, replace_own: bool = False) -> Train:
    """The train with an unbalance ``amount_kg_m`` added at ``station`` of ``rotor`` (default: its middle
    station), along +x at t = 0 (the keyphasor mark) turned by ``angle_rad``. ``replace_own``: drop the train's
    own unbalances first (a shaft line's residual one, ``ShaftLine.generator_unbalance_kg_m``), so that the
    given amount is the only one and is not added to it."""
    if not (math.isfinite(amount_kg_m) and 0.0 <= amount_kg_m <= 100.0):
        raise TrainError(f"unbalance amount_kg_m must be within 0..100 kg·m, got {amount_kg_m!r}")
    if not 0 <= rotor < len(train.rotors):
        raise TrainError(f"rotor must be 0..{len(train.rotors) - 1}, got {rotor!r}")
    r = train.rotors[rotor]
    k = r.n_stations // 2 if station is None else int(station)
    if not 0 <= k < r.n_stations:
        raise TrainError(f"station must be 0..{r.n_stations - 1} on rotor {r.name!r}, got {station!r}")
    rotors = [replace(x, unbalances=()) for x in train.rotors] if replace_own else list(train.rotors)
    own = rotors[rotor].unbalances
    if amount_kg_m > 0 or not replace_own:
        own = own + (Unbalance(k, float(amount_kg_m), float(angle_rad)),)
    rotors[rotor] = replace(rotors[rotor], unbalances=own)
    return replace(train, rotors=tuple(rotors))
