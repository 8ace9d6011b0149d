"""The rotor as a one-parameter family of Poincaré maps, and its branches in speed or Δ."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotordiag.core.numerics import DEFAULT_ATOL, DEFAULT_RTOL

from ..params import MISALIGNMENT_RANGE, SPEED_RANGE_RPM, Plant
from ..system import RotorSystem
from .continuation import Branch, continue_branch, switch_period_doubling
from .maps import RotorMap
from .shooting import steady_state

__all__ = ["RotorFamily", "rotor_branches", "brute_force_start", "PARAMETERS"]

#: continuation parameter -> (scale of s = p / scale, valid range)
PARAMETERS: dict[str, tuple[float, tuple[float, float]]] = {
    "speed_rpm": (1000.0, SPEED_RANGE_RPM),
    "misalignment": (1.0, MISALIGNMENT_RANGE),
}


@dataclass
class RotorFamily:
    """P of the rotor as a function of ``parameter`` ("speed_rpm" or "misalignment"), all else fixed."""

    plant: Plant
    parameter: str
    speed_rpm: float
    misalignment: float
    unbalance: float
    mechanism: str = "pin"
    rtol: float = DEFAULT_RTOL
    atol: float = DEFAULT_ATOL
    system_kwargs: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.parameter not in PARAMETERS:
            raise ValueError(f"parameter must be one of {tuple(PARAMETERS)}, got {self.parameter!r}")
        if self.parameter == "misalignment" and self.mechanism in ("pin",):
            # pin is singular at Δ = 0 (φ'' ∝ 1/Δ) and Δ = 0 switches to `aligned`: stay above
            self.floor = 1e-3
        else:
            self.floor = 0.0
        self.scale = PARAMETERS[self.parameter][0]
        self._cache: dict[float, RotorMap] = {}

    def system(self, value: float) -> RotorSystem:
        kw = dict(speed_rpm=self.speed_rpm, misalignment=self.misalignment)
        kw[self.parameter] = float(value)
        return RotorSystem(self.plant, kw["speed_rpm"], kw["misalignment"], self.unbalance, mechanism=self.mechanism,
                           rtol=self.rtol, atol=self.atol, **self.system_kwargs)

    def at(self, value: float) -> RotorMap:
        v = float(value)
        if v not in self._cache:
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[v] = RotorMap(self.system(v))
        return self._cache[v]

    def node_sections(self, value: float, sections: np.ndarray, node: int = 3, direction: int = 0) -> np.ndarray:
        """Poincaré coordinate (x or y of ``node``, / c) of each reduced section state."""
        pmap = self.at(value)
        full = np.array([pmap.full(s) for s in np.atleast_2d(sections)])
        pos = pmap.system.node_positions(np.zeros(len(full)), full)
        return pos[:, node - 1, direction] / self.plant.clearance_m


def rotor_branches(family: RotorFamily, start: float, stop: float, *, max_points: int = 150, ds: float = 0.02,
                   ds_max: float = 0.05, switch: bool = True, max_switches: int = 2,
                   start_state: np.ndarray | None = None, period: int | None = None,
                   start_revs: int = 0, bounds: tuple[float, float] | None = None) -> list[Branch]:
    """Branches from ``start`` toward ``stop`` (either order): the periodic orbit found by
    shooting at ``start`` (after a warm-up from MODEL.md's state), continued by pseudo-arclength
    (through folds, back and forth), plus the period-doubled branches switched onto at each
    located period-doubling point (up to ``max_switches``).

    ``start_revs`` > 0 starts from a brute-force point instead: that many revolutions integrated
    from MODEL.md's state (or ``start_state``), then 48 recorded; shooting for the period the
    record shows (or ``period``) from the end state. This is how an orbit inside a period-n window
    is reached (:func:`brute_force_start`).

    The branches stop where the parameter leaves [``start``, ``stop``] (sorted), or ``bounds`` when
    given (e.g. both sides of a window's start point: a branch that turns at a fold comes back past
    its start); or where they close on themselves (an isola)."""
    lo_valid, hi_valid = PARAMETERS[family.parameter][1]
    lo, hi = sorted((float(start), float(stop)))
    if bounds is not None:
        lo, hi = sorted((float(bounds[0]), float(bounds[1])))
        if not lo <= start <= hi:
            raise ValueError(f"the start {start:g} lies outside the bounds [{lo:g}, {hi:g}]")
    lo, hi = max(lo, lo_valid, family.floor), min(hi, hi_valid)
    if not lo < hi:
        raise ValueError(f"empty range for {family.parameter}: [{start}, {stop}]")
    kw: dict[str, Any] = {family.parameter: float(start)}
    kw = dict(speed_rpm=family.speed_rpm, misalignment=family.misalignment) | kw
    warmup = 40
    if start_revs > 0:
        start_state, found = brute_force_start(family, float(start), int(start_revs), start_state)
        if period is None and found is None:
            raise ValueError(f"no period <= 16 in the brute-force record at {family.parameter} = {start:g} after "
                             f"{start_revs} revolutions (quasi-periodic, chaotic or still settling)")
        period = period if period is not None else found
        warmup = 0
    orbit = steady_state(family.plant, kw["speed_rpm"], kw["misalignment"], family.unbalance,
                         mechanism=family.mechanism, rtol=family.rtol, atol=family.atol, period=period,
                         initial_state=start_state, warmup_revs=warmup, **family.system_kwargs)
    if not orbit.converged:
        raise ValueError(f"no periodic steady state at {family.parameter} = {start:g}: {orbit.message}")
    pmap = family.at(float(start))
    x0 = pmap.reduce(orbit.state)
    direction = 1 if stop > start else -1
    main = continue_branch(family, x0, float(start), n_periods=orbit.period, p_min=lo, p_max=hi,
                           direction=direction, ds=ds, ds_max=ds_max, max_points=max_points)
    branches = [main]
    if switch:
        todo = [(main, b) for b in main.bifurcations if b.kind == "period_doubling" and b.located]
        while todo and len(branches) <= max_switches:
            parent, bif = todo.pop(0)
            if parent.n_periods * 2 > 16:
                continue
            child = switch_period_doubling(family, parent, bif, ds=ds * 0.5, ds_max=ds_max, p_min=lo, p_max=hi,
                                           max_points=max_points)
            if len(child.points) > 1:
                branches.append(child)
                todo += [(child, b) for b in child.bifurcations if b.kind == "period_doubling" and b.located]
    return branches


#: revolutions recorded by :func:`brute_force_start` (three repeats of the longest period, 16)
START_RECORD_REVS = 48


def brute_force_start(family: RotorFamily, value: float, revs: int,
                      initial_state: np.ndarray | None = None) -> tuple[np.ndarray, int | None]:
    """End state and least period (≤ 16, None if none) of a brute-force run at ``value``:
    ``revs`` transient revolutions, then :data:`START_RECORD_REVS` recorded (``detect_period``,
    the sweeps' test)."""
    # the package's lazy attribute, as everywhere else: importing the submodule (``from ..simulate
    # import simulate``) before anyone read it rebinds rotordiag.simulator.simulate to the module
    from rotordiag.simulator import simulate

    from ..motion import detect_period

    if revs < 1:
        raise ValueError(f"revs must be >= 1, got {revs!r}")
    sysm = family.system(value)
    res = simulate(family.plant, sysm.speed_rpm, sysm.misalignment, family.unbalance, mechanism=family.mechanism,
                   transient_revs=int(revs), record_revs=START_RECORD_REVS, samples_per_rev=8, rtol=family.rtol,
                   atol=family.atol, initial_state=initial_state, **family.system_kwargs)
    if res.status != "ok":
        raise ValueError(f"the brute-force start at {family.parameter} = {value:g} ended with status {res.status!r}")
    n, _, _ = detect_period(res.poincare_m / res.clearance_m)
    return res.final_state, n


def _finite(v: float) -> bool:
    return math.isfinite(v)
