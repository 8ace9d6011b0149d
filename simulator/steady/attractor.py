"""A transient that ends once the motion has reached its attractor (the fallback of the shooting start).

Where the shooting start (:mod:`.start`) finds no stable period-1 orbit — oil whirl/whip
(quasi-periodic), period-n or chaotic motion — the record used to follow the full
brute-force transient (``transient_revs``, 400 revolutions as in the paper), although
most of these samples reach their attractor much sooner. :func:`settle_on_attractor`
integrates that transient in windows of ``window_revs`` revolutions and stops as soon as
the **statistics of the stroboscopic (Poincaré) points** no longer change: for each of
the six nodes' x and y (non-dimensional, X = x/c) the mean and the standard deviation
over a window — the static position with the 1X response, and the size of the
non-synchronous motion — must agree with those of the previous window within ``tol``
(absolute, in clearances) for ``STATIONARY_WINDOWS`` comparisons in a row, and at least
``min_revs`` revolutions must have run. It never integrates more than ``max_revs`` (the
old fixed transient), so a motion that does not settle (e.g. a slowly drifting chaotic
one, or a whirl still growing) gets exactly the old transient.

The windows are the same revolutions the fixed transient integrates (one trajectory,
restarted at every window boundary: for periodic and quasi-periodic motion the states
agree with one long run to the integrator's error; a chaotic run becomes another
realisation of the same attractor). What the record looks like after an early stop, against
the 400-revolution record and against that record's own spread (400 vs 800 revolutions),
is in docs/datasets.md (``benchmarks/bench_dataset.py --steady-start``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..system import TWO_PI, RotorSystem
from .start import SteadyStart, steady_start

__all__ = ["Settled", "settle_on_attractor", "record_start", "TRANSIENT_STOPS", "JOURNAL_NODES", "STATIONARY_TOL", "STATIONARY_WINDOW_REVS",
           "STATIONARY_MIN_REVS", "STATIONARY_WINDOWS", "STATIONARY_BLOCK",
           "STATIONARY_SAMPLES_PER_REV", "UNSTABLE_GROWTH"]

#: largest change (clearances) of a block's mean or standard deviation against the previous block
STATIONARY_TOL = 0.02
#: revolutions per window (the test runs at the end of every window)
STATIONARY_WINDOW_REVS = 32
#: windows per block: each test compares the last BLOCK windows with the BLOCK windows before them
STATIONARY_BLOCK = 1
#: revolutions always integrated before the test may stop the transient
STATIONARY_MIN_REVS = 128
#: consecutive tests within the tolerance required
STATIONARY_WINDOWS = 2
#: journal positions sampled per revolution for the statistics
STATIONARY_SAMPLES_PER_REV = 16
#: growth an unstable period-1 orbit's leading mode needs from the warm-up to a saturated whirl (1e-3 c to 1 c):
#: the transient runs at least ln(GROWTH) / ln max|μ| revolutions before the test may stop it
UNSTABLE_GROWTH = 1e3


@dataclass
class Settled:
    """Outcome of :func:`settle_on_attractor`.

    Attributes
    ----------
    state : ndarray
        Full non-dimensional state after ``revs`` revolutions (τ ≡ 0 mod 2π).
    revs : int
        Revolutions integrated.
    stationary : bool
        The test passed (False: ``max_revs`` reached, or the run ended with ``status`` ≠ "ok").
    change : float
        The last block-to-block change (clearances; NaN before the first test).
    status : {"ok", "contact", "diverged"}
    nfev : int
    """

    state: np.ndarray
    revs: int
    stationary: bool
    change: float
    status: str
    nfev: int


#: the journals (nodes 1, 3, 4, 6: what the probes at bearings 1–4 see) among the six nodes
JOURNAL_NODES = (0, 2, 3, 5)


def _moments(system: RotorSystem, tau: np.ndarray, states: np.ndarray) -> np.ndarray:
    """Count, sum and sum of squares of the journals' positions (clearances), shape (3, 4, 2)."""
    pos = system.node_positions(tau, states)[:, JOURNAL_NODES] / system.plant.clearance_m
    return np.stack([np.full(pos.shape[1:], float(len(pos))), pos.sum(axis=0), (pos ** 2).sum(axis=0)])


def _mean_std(m: np.ndarray) -> np.ndarray:
    """Mean and standard deviation from pooled moments, shape (2, 4, 2)."""
    mean = m[1] / m[0]
    return np.stack([mean, np.sqrt(np.maximum(m[2] / m[0] - mean ** 2, 0.0))])


def settle_on_attractor(system: RotorSystem, state: np.ndarray, max_revs: int, *,
                        min_revs: int = STATIONARY_MIN_REVS, window_revs: int = STATIONARY_WINDOW_REVS,
                        tol: float = STATIONARY_TOL, windows: int = STATIONARY_WINDOWS,
                        block: int = STATIONARY_BLOCK,
                        samples_per_rev: int = STATIONARY_SAMPLES_PER_REV) -> Settled:
    """Integrate from ``state`` (τ = 0) until the journals' motion statistics are stationary, at most ``max_revs``.

    Parameters
    ----------
    system : RotorSystem
        The operating point.
    state : ndarray, shape (n_state,)
        Start (full non-dimensional state at τ ≡ 0).
    max_revs : int
        Most revolutions (the fixed transient this replaces); ≤ 0 integrates nothing.
    min_revs : int
        Revolutions always integrated (counted from ``state``).
    window_revs : int
        Revolutions per window; the test runs after each.
    tol : float
        Largest change (clearances) of any journal coordinate's mean or standard deviation between blocks.
    windows : int
        Consecutive tests within ``tol`` required.
    block : int
        Windows per block.
    samples_per_rev : int
        Journal positions per revolution entering the statistics.

    Returns
    -------
    Settled
    """
    max_revs, window_revs, block = int(max_revs), int(window_revs), int(block)
    if window_revs < 1 or block < 1 or int(samples_per_rev) < 1:
        raise ValueError("window_revs, block and samples_per_rev must be >= 1, got "
                         f"{window_revs!r}, {block!r}, {samples_per_rev!r}")
    if not tol > 0:
        raise ValueError(f"tol must be > 0, got {tol!r}")
    y = system.check_state(state)
    spr = int(samples_per_rev)
    revs = nfev = streak = 0
    change = float("nan")
    moments: list[np.ndarray] = []
    while revs < max_revs:
        k = min(window_revs, max_revs - revs)
        dt = TWO_PI / spr
        y_new, grid, _, stats, ng, _ = system.integrate(y, 0.0, TWO_PI * k, grid_t0=dt, grid_dt=dt, n_grid=k * spr)
        nfev += stats.nfev
        if stats.status != "ok":
            return Settled(y, revs, False, change, stats.status, nfev)
        y, revs = y_new, revs + k
        if k < window_revs:  # the last, partial window: max_revs reached
            break
        moments.append(_moments(system, dt * (1 + np.arange(ng)), grid[:ng]))
        if len(moments) >= 2 * block:
            cur = _mean_std(np.sum(moments[-block:], axis=0))
            prev = _mean_std(np.sum(moments[-2 * block:-block], axis=0))
            change = float(np.max(np.abs(cur - prev)))
            streak = streak + 1 if change <= tol else 0
            if streak >= windows and revs >= min_revs:
                return Settled(y, revs, True, change, "ok", nfev)
    return Settled(y, revs, False, change, "ok", nfev)


#: how a fallback's transient ends: "stationary" (:func:`settle_on_attractor`) or "fixed" (all of it)
TRANSIENT_STOPS = ("stationary", "fixed")


def record_start(system: RotorSystem, transient_revs: int, method: str = "shooting",
                 transient_stop: str = "stationary") -> SteadyStart:
    """:func:`.start.steady_start`, then, for a shooting start that falls back, the stationary transient.

    With ``method="shooting"`` and ``transient_stop="stationary"`` a sample that falls back to
    integration runs :func:`settle_on_attractor` from where the warm-up stopped (the warm-up's
    revolutions count toward ``min_revs`` and ``max_revs``); the returned start's
    ``transient_revs`` is 0 (the record starts where the settling stopped) and its
    ``note`` begins with ``"transient N/T revs (stationary)"`` or ``"(not stationary)"``.
    ``method="integrate"`` and ``transient_stop="fixed"`` give :func:`.start.steady_start`'s start unchanged.
    A run that ends in contact or divergence during the settling keeps the fixed transient (the
    record's own run then reports it).
    """
    if transient_stop not in TRANSIENT_STOPS:
        raise ValueError(f"transient_stop must be one of {TRANSIENT_STOPS}, got {transient_stop!r}")
    start = steady_start(system, transient_revs, method)
    if method != "shooting" or transient_stop != "stationary" or start.path != "integrate" \
            or start.transient_revs <= 0 or start.warmup_revs == 0 or start.max_multiplier <= 1.0:
        return start
    min_revs = STATIONARY_MIN_REVS
    if math.isfinite(start.max_multiplier):  # an unstable orbit: its whirl needs time to grow, however slowly
        min_revs = max(min_revs, math.ceil(math.log(UNSTABLE_GROWTH) / math.log(start.max_multiplier)))
    if min_revs >= int(transient_revs):
        return start
    st = settle_on_attractor(system, start.state, start.transient_revs, min_revs=min_revs - start.warmup_revs)
    if st.status != "ok":
        return start
    used = start.warmup_revs + st.revs
    word = "stationary" if st.stationary else "not stationary"
    # the record starts where the settling stopped: nothing of the fixed transient is left to integrate
    return replace(start, state=st.state, transient_revs=0,
                   note=f"transient {used}/{int(transient_revs)} revs ({word}); {start.note}",
                   nfev=start.nfev + st.nfev)
