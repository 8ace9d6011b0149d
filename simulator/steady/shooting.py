"""Newton shooting on the Poincaré map: periodic steady states and their Floquet multipliers.

A period-n steady state is a fixed point of Pⁿ (P = one revolution from τ ≡ 0).
:func:`find_fixed_point` solves Pⁿ(x) − x = 0 by Newton's method with the
monodromy matrix M = ∂Pⁿ/∂x from the variational equations, and a backtracking
line search (the residual must fall) for starts far from the orbit. The Floquet
multipliers are the eigenvalues of M at the converged point: |μ| < 1 for all of
them is a stable orbit, any |μ| > 1 an unstable one (it exists, but no
integration from a nearby start stays on it).

``method="chord"`` (what :func:`steady_state` uses by default) reuses one cheap
monodromy matrix (rtol 1e-3) for all iterations, each of which then costs one plain
map evaluation; it converges to the same fixed point and hands over to Newton if it
stalls.

:func:`steady_state` is the rotor entry point: build the system, warm up by
integration (at most ``warmup_revs``, ending once the Poincaré points settle; the
warm-up also proposes the period n ≤ 16 from their recurrence), shoot, and return a
:class:`PeriodicOrbit` with the orbit sampled over its n revolutions. Measured at
1950 r/min on one core (``benchmarks/bench_steady.py``): 15–19 ms per period-1
point from MODEL.md's start with exact multipliers, against 75–101 ms for 400
brute-force revolutions.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotordiag.core.numerics import DEFAULT_ATOL, DEFAULT_RTOL

from ..motion import detect_period
from ..params import Plant
from ..system import TWO_PI, RotorSystem
from .maps import MapEval, PeriodicMap, RotorMap

__all__ = [
    "FixedPoint", "PeriodicOrbit", "find_fixed_point", "steady_state", "stability_verdict",
    "MAX_PERIOD", "NEWTON_TOL", "MULTIPLIER_TOL", "CHORD_JACOBIAN_RTOL", "METHODS",
]

#: longest period searched (MODEL.md §8)
MAX_PERIOD = 16
#: Newton stops when max |Pⁿ(x) − x| (non-dimensional) is below this
NEWTON_TOL = 1e-9
#: |μ| within this of 1 is reported "marginal" (the multipliers' accuracy is ~1e-7)
MULTIPLIER_TOL = 1e-5
#: largest Newton step (non-dimensional, ∞-norm): a far start is pulled in, not thrown out
MAX_NEWTON_STEP = 0.2
#: relative tolerance of the approximate monodromy matrix of the chord iterations
#: (M to ~3e-4 relative, |μ| to ~1e-5, at about a quarter of the cost of an rtol-1e-6 matrix)
CHORD_JACOBIAN_RTOL = 1e-3
#: a chord step must cut the residual at least by this factor, else the matrix is recomputed
CHORD_CONTRACTION = 0.5
METHODS = ("newton", "chord")


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
                     max_iter: int = 30, max_step: float = MAX_NEWTON_STEP, method: str = "newton",
                     jacobian_rtol: float | None = None, exact_multipliers: bool = True,
                     newton_fallback: bool = True) -> FixedPoint:
    """Newton's method (or chord iterations) on Pⁿ(x) − x = 0 with the variational monodromy matrix.

    ``method="chord"``: one monodromy matrix M (at the start, optionally at a looser
    ``jacobian_rtol``; recomputed only when a step fails to halve the residual) is
    LU-factorised once and reused: each further iteration costs one plain map
    evaluation (≈ 1/20 to 1/40 of a monodromy). It converges linearly, at a rate
    ≈ ‖(M − I)⁻¹ δM‖ (≈ 1e-2 from a start near the orbit), to the fixed point of the
    same map Pⁿ as Newton. When the chord iterations stall, Newton with its line search
    continues from the best point reached. With ``exact_multipliers`` one monodromy
    matrix at the system's tolerance is evaluated at the converged point (the Floquet
    multipliers are then as accurate as Newton's); without it the multipliers are
    those of the last chord matrix, evaluated at a point within a chord step of the
    orbit (|μ| to ~1e-4 at ``jacobian_rtol`` 1e-3), enough for a stability verdict
    away from |μ| = 1.

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
    method : {"newton", "chord"}
    jacobian_rtol : float, optional
        Chord only: relative tolerance of the chord matrix (``CHORD_JACOBIAN_RTOL`` is
        a good value; default the map's own). Needs a map whose ``evaluate`` takes ``rtol``.
    exact_multipliers : bool
        Chord only: see above.
    newton_fallback : bool
        Chord only: let Newton continue when the chord iterations stall (default); False
        returns the chord's failure (a caller that falls back to integration anyway).
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    x = np.array(x0, dtype=float, copy=True)
    nfev = 0
    if method == "chord":
        chord = _chord(pmap, x, int(n_periods), tol, max_iter, max_step, jacobian_rtol, exact_multipliers)
        if chord.converged or not newton_fallback:
            return chord
        x = chord.x  # best point reached: Newton continues from there
        nfev = chord.nfev
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


def _chord(pmap: PeriodicMap, x: np.ndarray, n: int, tol: float, max_iter: int, max_step: float,
           jacobian_rtol: float | None, exact_multipliers: bool) -> FixedPoint:
    """Chord iterations (see :func:`find_fixed_point`); not converged: ``x`` is the best point reached."""
    from scipy.linalg import lu_factor, lu_solve

    kw = {} if jacobian_rtol is None else {"rtol": float(jacobian_rtol)}
    ev = pmap.evaluate(x, n)
    nfev = ev.nfev
    if not ev.ok:
        return _fail(x, ev, nfev, 0, f"the start state's run ended with status {ev.status!r}")
    r = pmap.difference(ev.value, x)
    rn = float(np.max(np.abs(r)))
    eye = np.eye(x.size)
    lu: Any = None
    monodromy: np.ndarray | None = None
    fresh = False
    n_matrices = 0
    it = 0
    while rn > tol:
        if it >= max_iter:
            return _fail(x, ev, nfev, it, f"chord: no convergence in {max_iter} iterations (residual {rn:.3e})")
        if lu is None:
            evm = pmap.evaluate(x, n, monodromy=True, **kw)
            nfev += evm.nfev
            if not evm.ok or evm.monodromy is None or not np.all(np.isfinite(evm.monodromy)):
                return _fail(x, ev, nfev, it, f"chord: monodromy run ended with status {evm.status!r}")
            monodromy = evm.monodromy
            lu = lu_factor(monodromy - eye, check_finite=False)
            fresh = True
            n_matrices += 1
        dx = lu_solve(lu, -r, check_finite=False)
        big = float(np.max(np.abs(dx)))
        if not math.isfinite(big):
            return _fail(x, ev, nfev, it, "chord: non-finite step (a multiplier at 1: fold?)")
        if big > max_step:
            dx *= max_step / big
        xt = x + dx
        evt = pmap.evaluate(xt, n)
        nfev += evt.nfev
        it += 1
        rtn = float(np.max(np.abs(pmap.difference(evt.value, xt)))) if evt.ok else math.inf
        if rtn <= CHORD_CONTRACTION * rn or rtn <= tol or (big < 0.1 * tol and rtn <= 10 * tol):
            x, ev, r, rn = xt, evt, pmap.difference(evt.value, xt), rtn
            fresh = False
            if big < 0.1 * tol:
                break  # the step is below the map's own noise
        elif fresh:
            return _fail(x, ev, nfev, it, f"chord: a fresh matrix does not contract (residual {rn:.3e} -> {rtn:.3e})")
        else:
            if rtn < rn:
                x, ev, r, rn = xt, evt, pmap.difference(evt.value, xt), rtn
            lu = None  # recompute the matrix where we are
    if rn > 10 * tol:
        return _fail(x, ev, nfev, it, f"chord stalled at residual {rn:.3e}")
    if exact_multipliers or monodromy is None:
        evm = pmap.evaluate(x, n, monodromy=True)
        nfev += evm.nfev
        if not evm.ok or evm.monodromy is None:
            return _fail(x, ev, nfev, it, f"monodromy run at the fixed point ended with status {evm.status!r}")
        monodromy = evm.monodromy
    return FixedPoint(x, monodromy, floquet_multipliers(monodromy), ev.sections, rn, True, it, nfev, ev.status,
                      f"converged (chord, {n_matrices} matrix evaluation(s))")


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
    method: str = "chord",
    jacobian_rtol: float | None = CHORD_JACOBIAN_RTOL,
    exact_multipliers: bool = True,
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
        Most revolutions integrated from the start before Newton (0: shoot from the
        start at once, right for a good ``initial_state``); the warm-up ends after
        the first 10-revolution chunk whose Poincaré points have settled (:func:`warm_up`).
    samples_per_rev : int
        Samples per revolution of the returned ``orbit``.
    rtol, atol : float
        Integrator tolerances of the map (the residual cannot fall much below the
        integration error: ``tol`` ≈ 1e-9 needs rtol ≲ 1e-6).
    tol, max_iter : float, int
        Newton tolerance (max |Pⁿ(x) − x|, non-dimensional) and iteration cap.
    central : bool
        Central directional differences in the variational equations.
    method : {"chord", "newton"}
        Chord iterations (one cheap monodromy matrix at ``jacobian_rtol``, reused; Newton
        takes over if they stall) or Newton with a monodromy matrix per iteration. Both
        converge to the same fixed point of the same map (see :func:`find_fixed_point`).
    jacobian_rtol : float, optional
        Chord only: tolerance of the chord matrix (None: ``rtol``).
    exact_multipliers : bool
        Chord only: evaluate the monodromy matrix at the fixed point at ``rtol`` for the
        multipliers (default); False reports the chord matrix's (|μ| to ~1e-4, one
        monodromy cheaper: what a dataset's stable/unstable decision needs).
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
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    solver = dict(tol=tol, max_iter=max_iter, method=method, jacobian_rtol=jacobian_rtol,
                  exact_multipliers=exact_multipliers)
    system = RotorSystem(plant, speed_rpm, misalignment, unbalance, mechanism=mechanism, rtol=rtol, atol=atol,
                         **system_kwargs)
    pmap = RotorMap(system, central=central)
    y0 = system.initial_state() if initial_state is None else system.check_state(initial_state)
    x0 = pmap.reduce(y0)
    nfev = 0
    settled = False
    if warmup_revs > 0:
        wu = warm_up(pmap, x0, int(warmup_revs))
        nfev += wu.nfev
        if not wu.ok:
            return _orbit_failed(system, y0, nfev, start, f"warm-up ended with status {wu.status!r}")
        x0, settled = wu.x, wu.settled
        recent = wu.sections[-min(len(wu.sections), 2 * MAX_PERIOD + 1):]
    else:
        recent = np.zeros((0, x0.size))
    if period is not None:
        periods = [int(period)]
    elif len(recent) > 2:
        periods = candidate_periods(recent)
        if settled:  # the warm-up's points contract onto one: period 1 first
            periods = [1] + [n for n in periods if n != 1][:2]
    else:
        periods = [1]
    messages = []
    for n in periods:
        fp = find_fixed_point(pmap, x0, n, **solver)  # type: ignore[arg-type]
        nfev += fp.nfev
        if fp.converged:
            n_least = _reduce_period(pmap, fp, n, tol) if period is None else n
            if n_least != n:
                fp = find_fixed_point(pmap, fp.x, n_least, **solver)  # type: ignore[arg-type]
                nfev += fp.nfev
                n = n_least
            if fp.converged:
                return _orbit(system, pmap, fp, n, nfev, start, samples_per_rev)
        messages.append(f"period {n}: {fp.message}")
    return _orbit_failed(system, pmap.full(x0), nfev, start, "; ".join(messages))


#: the warm-up runs in chunks of this many revolutions (and at least one chunk)
WARMUP_CHUNK_REVS = 10
#: the warm-up ends early once consecutive Poincaré points differ by less than this (∞-norm,
#: non-dimensional) and the differences have fallen over the last chunk: period-1 motion settling
WARMUP_SETTLED = 1e-2


@dataclass
class WarmUp:
    """Outcome of :func:`warm_up` (reduced states)."""

    x: np.ndarray
    sections: np.ndarray
    revs: int
    settled: bool
    status: str
    nfev: int

    @property
    def ok(self) -> bool:
        return self.status == "ok"


def warm_up(pmap: RotorMap, x0: np.ndarray, max_revs: int, *, chunk_revs: int = WARMUP_CHUNK_REVS,
            settled_tol: float = WARMUP_SETTLED) -> WarmUp:
    """Integrate up to ``max_revs`` revolutions from ``x0`` in chunks, ending early once settled.

    Settled: the last two Poincaré points differ by at most ``settled_tol`` and by no more
    than the first two of the chunk (the differences fall: a period-1 orbit being approached;
    period-n, quasi-periodic and chaotic motion never settle this way). The revolutions are
    the same ones a brute-force transient integrates (``x`` after k of them is that
    run's state at revolution k, up to the integrator's restart at each chunk).
    """
    x = np.array(x0, dtype=float, copy=True)
    pts: list[np.ndarray] = []
    nfev, done, last = 0, 0, x
    while done < max_revs:
        k = min(int(chunk_revs), max_revs - done)
        ev = pmap.evaluate(x, k)
        nfev += ev.nfev
        if not ev.ok:
            return WarmUp(x, np.array(pts).reshape(-1, x.size), done, False, ev.status, nfev)
        pts.extend(ev.sections)
        done += k
        chain = np.vstack([last[None, :], ev.sections])
        d = np.max(np.abs(pmap.difference(chain[1:], chain[:-1])), axis=1)
        x, last = ev.value, ev.value
        if d[-1] <= settled_tol and d[-1] <= max(d[0], 1e-7):
            return WarmUp(x, np.array(pts), done, True, "ok", nfev)
    return WarmUp(x, np.array(pts).reshape(-1, x.size), done, False, "ok", nfev)


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
