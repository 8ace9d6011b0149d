"""Newton shooting on the Poincaré map: periodic steady states and their Floquet multipliers.

A period-n steady state is a fixed point of Pⁿ (P = one revolution from τ ≡ 0).
:func:`find_fixed_point` solves Pⁿ(x) − x = 0 by Newton's method with the
monodromy matrix M = ∂Pⁿ/∂x from the variational equations, and a backtracking
line search (the residual must fall) for starts far from the orbit. The Floquet
multipliers are the eigenvalues of M at the converged point: |μ| < 1 for all of
them is a stable orbit, any |μ| > 1 an unstable one (it exists, but no
integration from a nearby start stays on it).

:func:`steady_state` is the rotor entry point: build the system, warm up by
integration (which also proposes the period n ≤ 16 from the recurrence of the
Poincaré points), shoot, and return a :class:`PeriodicOrbit` with the orbit
sampled over its n revolutions.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotordiag.core.numerics import DEFAULT_ATOL, DEFAULT_RTOL

from ..analysis.motion import detect_period
from ..params import Plant
from ..system import TWO_PI, RotorSystem
from .maps import MapEval, PeriodicMap, RotorMap

__all__ = [
    "FixedPoint", "PeriodicOrbit", "find_fixed_point", "steady_state", "stability_verdict",
    "MAX_PERIOD", "NEWTON_TOL", "MULTIPLIER_TOL",
]

#: longest period searched (MODEL.md §8)
MAX_PERIOD = 16
#: Newton stops when max |Pⁿ(x) − x| (non-dimensional) is below this
NEWTON_TOL = 1e-9
#: |μ| within this of 1 is reported "marginal" (the multipliers' accuracy is ~1e-7)
MULTIPLIER_TOL = 1e-5
#: largest Newton step (non-dimensional, ∞-norm): a far start is pulled in, not thrown out
MAX_NEWTON_STEP = 0.2


def stability_verdict(multipliers: np.ndarray, tol: float = MULTIPLIER_TOL) -> str:
    """"stable" (all |μ| < 1 − tol), "unstable" (some |μ| > 1 + tol) or "marginal"."""
    mod = np.abs(np.asarray(multipliers))
    if mod.size == 0 or mod.max() < 1.0 - tol:
        return "stable"
    if mod.max() > 1.0 + tol:
        return "unstable"
    return "marginal"


def floquet_multipliers(monodromy: np.ndarray) -> np.ndarray:
    """Eigenvalues of the monodromy matrix, largest modulus first."""
    mu = np.linalg.eigvals(monodromy)
    return mu[np.lexsort((-mu.imag, -np.abs(mu)))]


@dataclass
class FixedPoint:
    """Outcome of :func:`find_fixed_point` (reduced coordinates of the map).

    Attributes
    ----------
    x : ndarray, shape (m,)
        Last iterate (the fixed point when ``converged``).
    monodromy : ndarray, shape (m, m) or None
        ∂Pⁿ/∂x at ``x``.
    multipliers : ndarray, complex
        Floquet multipliers (eigenvalues of ``monodromy``), largest modulus first.
    sections : ndarray, shape (n, m)
        P(x), …, Pⁿ(x) (the n points of the orbit in the section; the last is ≈ x).
    residual : float
        max |Pⁿ(x) − x| at ``x``.
    converged : bool
    iterations : int
        Newton iterations (monodromy evaluations − 1).
    nfev : int
    status : str
        The integrator's status of the last evaluation.
    message : str
    """

    x: np.ndarray
    monodromy: np.ndarray | None
    multipliers: np.ndarray
    sections: np.ndarray
    residual: float
    converged: bool
    iterations: int
    nfev: int
    status: str
    message: str

    @property
    def stability(self) -> str:
        return stability_verdict(self.multipliers) if self.converged else "unknown"


def find_fixed_point(pmap: PeriodicMap, x0: np.ndarray, n_periods: int = 1, *, tol: float = NEWTON_TOL,
                     max_iter: int = 30, max_step: float = MAX_NEWTON_STEP) -> FixedPoint:
    """Newton's method on Pⁿ(x) − x = 0 with the variational monodromy matrix.

    Parameters
    ----------
    pmap : PeriodicMap
        E.g. :class:`RotorMap`.
    x0 : ndarray, shape (m,)
        Start (reduced state).
    n_periods : int
        n (1..16 for the rotor).
    tol : float
        Convergence: max |Pⁿ(x) − x| ≤ tol (≤ 10·tol once the Newton step is below tol/10).
    max_iter, max_step
        Iteration cap; the largest step (∞-norm) before the line search.
    """
    x = np.array(x0, dtype=float, copy=True)
    nfev = 0
    ev = pmap.evaluate(x, n_periods, monodromy=True)
    nfev += ev.nfev
    if not ev.ok:
        return _fail(x, ev, nfev, 0, f"the start state's run ended with status {ev.status!r}")
    r = pmap.difference(ev.value, x)
    rn = float(np.max(np.abs(r)))
    eye = np.eye(x.size)
    small_step = False
    for it in range(1, max_iter + 1):
        if rn <= tol or (small_step and rn <= 10 * tol):
            return _done(x, ev, rn, it - 1, nfev, "converged")
        assert ev.monodromy is not None
        try:
            dx = np.linalg.solve(ev.monodromy - eye, -r)
        except np.linalg.LinAlgError:
            return _fail(x, ev, nfev, it - 1, "singular Jacobian (a multiplier at exactly 1: fold)")
        big = float(np.max(np.abs(dx)))
        if not math.isfinite(big):
            return _fail(x, ev, nfev, it - 1, "non-finite Newton step")
        if big > max_step:
            dx *= max_step / big
        lam = 1.0
        while True:
            xt = x + lam * dx
            evt = pmap.evaluate(xt, n_periods, monodromy=lam == 1.0)
            nfev += evt.nfev
            rt = pmap.difference(evt.value, xt) if evt.ok else None
            rtn = float(np.max(np.abs(rt))) if rt is not None else math.inf
            if rtn < rn * (1.0 - 1e-4 * lam) or (rtn <= tol) or big * lam < tol * 0.1:
                break
            lam *= 0.25
            if lam < 1e-3:
                return _fail(x, ev, nfev, it, f"line search failed (residual {rn:.3e})")
        if evt.monodromy is None:
            evt = pmap.evaluate(xt, n_periods, monodromy=True)
            nfev += evt.nfev
            rt = pmap.difference(evt.value, xt)
            rtn = float(np.max(np.abs(rt)))
        assert rt is not None
        x, ev, r, rn = xt, evt, rt, rtn
        small_step = big * lam < tol * 0.1
        if big * lam < tol * 0.1 and rn > 10 * tol:
            return _fail(x, ev, nfev, it, f"Newton stalled at residual {rn:.3e} (integration noise above tol?)")
    if rn <= 10 * tol:
        return _done(x, ev, rn, max_iter, nfev, "converged")
    return _fail(x, ev, nfev, max_iter, f"no convergence in {max_iter} iterations (residual {rn:.3e})")


def _done(x: np.ndarray, ev: MapEval, rn: float, it: int, nfev: int, msg: str) -> FixedPoint:
    assert ev.monodromy is not None
    return FixedPoint(x, ev.monodromy, floquet_multipliers(ev.monodromy), ev.sections, rn, True, it, nfev,
                      ev.status, msg)


def _fail(x: np.ndarray, ev: MapEval, nfev: int, it: int, msg: str) -> FixedPoint:
    return FixedPoint(x, ev.monodromy, np.array([], dtype=complex), ev.sections, math.inf, False, it, nfev,
                      ev.status, msg)


# ---------------------------------------------------------------- the rotor
@dataclass
class PeriodicOrbit:
    """A periodic steady state of the rotor found by shooting.

    Attributes
    ----------
    period : int
        n: the orbit repeats after n revolutions (0 when not converged).
    state : ndarray, shape (n_state,)
        Non-dimensional state at τ ≡ 0 (pass to ``simulate(initial_state=...)``).
    sections : ndarray, shape (n, n_state)
        The n Poincaré points (states at τ = 2πk, k = 1..n; the last equals ``state``).
    multipliers : ndarray, complex
        Floquet multipliers of Pⁿ, largest modulus first.
    stability : {"stable", "unstable", "marginal", "unknown"}
    converged : bool
    residual : float
        max |Pⁿ(x) − x| (non-dimensional).
    iterations, nfev : int
    wall_time_s : float
    message : str
    tau : ndarray, shape (n·S,)
        Phases of the orbit samples (τ = 2πk/S, k = 0..n·S − 1).
    orbit : ndarray, shape (n·S, n_state)
        The orbit over its n revolutions (dense output of one integration from ``state``).
    inputs : dict
    """

    period: int
    state: np.ndarray
    sections: np.ndarray
    multipliers: np.ndarray
    stability: str
    converged: bool
    residual: float
    iterations: int
    nfev: int
    wall_time_s: float
    message: str
    tau: np.ndarray = field(default_factory=lambda: np.zeros(0))
    orbit: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    inputs: dict[str, Any] = field(default_factory=dict)

    @property
    def max_multiplier(self) -> float:
        """Largest |μ| (NaN when not converged)."""
        return float(np.abs(self.multipliers).max()) if self.multipliers.size else math.nan

    @property
    def stable(self) -> bool:
        return self.stability == "stable"


def candidate_periods(points: np.ndarray, max_period: int = MAX_PERIOD, n_candidates: int = 3) -> list[int]:
    """Periods to try, best first: the smallest n whose recurrence distance is within 2× of the best."""
    pts = np.asarray(points, dtype=float)
    d = np.full(max_period, np.inf)
    _, dist, _ = detect_period(pts, orbit_size=1.0, max_period=max_period, min_repeats=2)
    d[:len(dist)] = dist
    order = [int(i) + 1 for i in np.argsort(d, kind="stable") if math.isfinite(d[i])]
    if not order:
        return [1]
    best = d[order[0] - 1]
    close = sorted(n for n in order if d[n - 1] <= 2.0 * best + 1e-12)
    rest = [n for n in order if n not in close]
    out: list[int] = []
    for n in close + rest:
        if all(n % m for m in out):  # a multiple of a tried period adds nothing new
            out.append(n)
        if len(out) >= n_candidates:
            break
    return out


def _reduce_period(pmap: RotorMap, fp: FixedPoint, n: int, tol: float) -> int:
    """Smallest divisor d of n with |P^d(x) − x| within tolerance (the orbit's least period)."""
    for d in range(1, n):
        if n % d == 0 and np.max(np.abs(pmap.difference(fp.sections[d - 1], fp.x))) <= 100 * tol:
            return d
    return n


def steady_state(
    plant: Plant,
    speed_rpm: float,
    misalignment: float,
    unbalance: float,
    *,
    mechanism: str = "pin",
    period: int | None = None,
    initial_state: np.ndarray | None = None,
    warmup_revs: int = 40,
    samples_per_rev: int = 64,
    rtol: float = DEFAULT_RTOL,
    atol: float = DEFAULT_ATOL,
    tol: float = NEWTON_TOL,
    max_iter: int = 30,
    central: bool = False,
    **system_kwargs: Any,
) -> PeriodicOrbit:
    """Periodic steady state of the rotor by shooting on the once-per-revolution map.

    Parameters
    ----------
    plant, speed_rpm, misalignment, unbalance, mechanism
        As for :func:`rotordiag.simulator.simulate` (every mechanism).
    period : int, optional
        n (1..16). Default: proposed from the warm-up's Poincaré points
        (the three most recurrent periods are tried, smallest first).
    initial_state : ndarray, optional
        Start (full state at τ ≡ 0), e.g. a neighbouring orbit's ``state``;
        default MODEL.md §5's start.
    warmup_revs : int
        Revolutions integrated from the start before Newton (0: shoot from the
        start at once, right for a good ``initial_state``).
    samples_per_rev : int
        Samples per revolution of the returned ``orbit``.
    rtol, atol : float
        Integrator tolerances of the map (the residual cannot fall much below the
        integration error: ``tol`` ≈ 1e-9 needs rtol ≲ 1e-6).
    tol, max_iter : float, int
        Newton tolerance (max |Pⁿ(x) − x|, non-dimensional) and iteration cap.
    central : bool
        Central directional differences in the variational equations.
    **system_kwargs
        ``unbalance_phase_rad``, ``offset_angle_rad``, ... (``RotorSystem``).

    Returns
    -------
    PeriodicOrbit
        ``converged`` False (with ``message``) when Newton fails for every candidate
        period: e.g. quasi-periodic or chaotic motion, which has no fixed point.
    """
    start = time.perf_counter()
    if period is not None and (isinstance(period, bool) or int(period) != period or not 1 <= period <= MAX_PERIOD):
        raise ValueError(f"period must be an integer in 1..{MAX_PERIOD}, got {period!r}")
    if int(warmup_revs) != warmup_revs or warmup_revs < 0:
        raise ValueError(f"warmup_revs must be an integer >= 0, got {warmup_revs!r}")
    system = RotorSystem(plant, speed_rpm, misalignment, unbalance, mechanism=mechanism, rtol=rtol, atol=atol,
                         **system_kwargs)
    pmap = RotorMap(system, central=central)
    y0 = system.initial_state() if initial_state is None else system.check_state(initial_state)
    x0 = pmap.reduce(y0)
    nfev = 0
    if warmup_revs > 0:
        ev = pmap.evaluate(x0, int(warmup_revs))
        nfev += ev.nfev
        if not ev.ok:
            return _orbit_failed(system, y0, nfev, start, f"warm-up ended with status {ev.status!r}")
        x0 = ev.value
        recent = ev.sections[-min(len(ev.sections), 2 * MAX_PERIOD + 1):]
    else:
        recent = np.zeros((0, x0.size))
    if period is not None:
        periods = [int(period)]
    elif len(recent) > 2:
        periods = candidate_periods(recent)
    else:
        periods = [1]
    messages = []
    for n in periods:
        fp = find_fixed_point(pmap, x0, n, tol=tol, max_iter=max_iter)
        nfev += fp.nfev
        if fp.converged:
            n_least = _reduce_period(pmap, fp, n, tol) if period is None else n
            if n_least != n:
                fp = find_fixed_point(pmap, fp.x, n_least, tol=tol, max_iter=max_iter)
                nfev += fp.nfev
                n = n_least
            if fp.converged:
                return _orbit(system, pmap, fp, n, nfev, start, samples_per_rev)
        messages.append(f"period {n}: {fp.message}")
    return _orbit_failed(system, pmap.full(x0), nfev, start, "; ".join(messages))


def _inputs(system: RotorSystem) -> dict[str, Any]:
    return dict(plant=system.plant.to_dict(), speed_rpm=system.speed_rpm, misalignment=system.misalignment,
                unbalance=system.unbalance, mechanism=system.mechanism, rtol=system.rtol, atol=system.atol)


def _orbit(system: RotorSystem, pmap: RotorMap, fp: FixedPoint, n: int, nfev: int, start: float,
           samples_per_rev: int) -> PeriodicOrbit:
    y = pmap.full(fp.x)
    s = int(samples_per_rev)
    _, grid, _, stats, ng, _ = system.integrate(y, 0.0, TWO_PI * n, grid_t0=0.0, grid_dt=TWO_PI / s, n_grid=n * s)
    sections = np.stack([pmap.full(v) for v in fp.sections])
    return PeriodicOrbit(
        period=n, state=y, sections=sections, multipliers=fp.multipliers, stability=fp.stability,
        converged=True, residual=fp.residual, iterations=fp.iterations, nfev=nfev + stats.nfev,
        wall_time_s=time.perf_counter() - start, message=fp.message,
        tau=TWO_PI / s * np.arange(ng), orbit=grid[:ng], inputs=_inputs(system),
    )


def _orbit_failed(system: RotorSystem, y: np.ndarray, nfev: int, start: float, msg: str) -> PeriodicOrbit:
    return PeriodicOrbit(
        period=0, state=y, sections=np.zeros((0, y.size)), multipliers=np.array([], dtype=complex),
        stability="unknown", converged=False, residual=math.inf, iterations=0, nfev=nfev,
        wall_time_s=time.perf_counter() - start, message=msg, inputs=_inputs(system),
    )
