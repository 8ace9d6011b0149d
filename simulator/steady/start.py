"""Where a steady-state record starts: on the shot orbit where that is safe, else after the transient.

Every dataset sample and sweep point used to integrate 400 transient revolutions
from MODEL.md §5's state and then record. :func:`steady_start` does the same
first revolutions (the warm-up of :func:`~.shooting.warm_up`, at most
``warmup_revs``) and, when they settle onto one point of the Poincaré section,
solves for the period-1 fixed point by chord iterations (:func:`find_fixed_point`)
and starts the record there, with no transient left. It falls back to integration,
continuing from where the warm-up stopped (no revolution is integrated twice),
whenever the shooting start would not give what the transient gives:

* the chord iterations from the warm-up's last point fail (no period-1 orbit near: period-n,
  quasi-periodic / whirl or chaotic motion);
* the orbit found is not clearly stable (max |μ| > ``MAX_START_MULTIPLIER``: near a
  bifurcation the transient itself has not converged after 400 revolutions, and
  an unstable orbit is never what a run shows);
* the warm-up is not approaching the orbit: its distance to the fixed point must fall by
  ``APPROACH_FACTOR`` over its last ``APPROACH_REVS`` revolutions, or, when the warm-up
  settled early, be within what geometric contraction at the rate max |μ| allows (else the
  transient is heading for another attractor).

The warm-up ends early (after 10, 20, 30 revolutions) once its Poincaré points settle.

The start's outcome (``path`` "shooting" or "integrate", and ``note``, why not
shooting) is what dataset records and sweep points report.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..system import RotorSystem
from .maps import RotorMap
from .shooting import CHORD_JACOBIAN_RTOL, find_fixed_point, warm_up

__all__ = ["SteadyStart", "steady_start", "STEADY_STARTS", "MAX_START_MULTIPLIER", "START_WARMUP_REVS"]

#: the ways a steady-state record may start
STEADY_STARTS = ("shooting", "integrate")
#: largest Floquet multiplier modulus the shooting start accepts (0.99**400 ≈ 0.018: a slower orbit
#: is not reached by the 400-revolution transient either, so the two would differ)
MAX_START_MULTIPLIER = 0.99
#: most warm-up revolutions before shooting (they count toward the transient)
START_WARMUP_REVS = 20
#: chord iterations allowed (each one plain revolution; no Newton after them: integration is the fallback)
START_MAX_ITER = 12
#: an unsettled warm-up must bring its distance to the orbit down by this factor over APPROACH_REVS revolutions
APPROACH_REVS = 15
APPROACH_FACTOR = 0.9


@dataclass
class SteadyStart:
    """Where to start recording.

    Attributes
    ----------
    state : ndarray, shape (n_state,)
        Full non-dimensional state at τ ≡ 0 (mod 2π): ``simulate(initial_state=...)``.
    transient_revs : int
        Revolutions still to integrate before recording (0 after a shooting start).
    path : {"shooting", "integrate"}
    note : str
        Why the start is "integrate" when shooting was asked for ("" otherwise).
    warmup_revs : int
        Revolutions the warm-up integrated (included in ``transient_revs``' budget).
    max_multiplier : float
        max |μ| of the orbit (NaN when none was found); from the chord matrix (|μ| to ~1e-4).
    nfev : int
    """

    state: np.ndarray
    transient_revs: int
    path: str
    note: str = ""
    warmup_revs: int = 0
    max_multiplier: float = float("nan")
    nfev: int = 0


def steady_start(system: RotorSystem, transient_revs: int, method: str = "shooting", *,
                 initial_state: np.ndarray | None = None, warmup_revs: int = START_WARMUP_REVS) -> SteadyStart:
    """Start state of a steady-state record (see the module docstring).

    Parameters
    ----------
    system : RotorSystem
        The operating point (its rtol/atol are those of the record).
    transient_revs : int
        The brute-force transient this start replaces (the budget of the fallback).
    method : {"shooting", "integrate"}
        "integrate" returns the start state and the whole transient unchanged (today's path).
    initial_state : ndarray, optional
        Default MODEL.md §5's start.
    warmup_revs : int
        Most revolutions integrated before shooting.
    """
    if method not in STEADY_STARTS:
        raise ValueError(f"steady_start must be one of {STEADY_STARTS}, got {method!r}")
    transient_revs = int(transient_revs)
    y0 = system.initial_state() if initial_state is None else system.check_state(initial_state)
    if method == "integrate" or transient_revs <= 0:
        return SteadyStart(y0, transient_revs, "integrate", "" if method == "integrate" else "no transient asked for")
    pmap = RotorMap(system)
    wu = warm_up(pmap, pmap.reduce(y0), min(int(warmup_revs), transient_revs))
    if not wu.ok:  # contact or divergence: the brute-force run reports it with its own message
        return SteadyStart(y0, transient_revs, "integrate", f"warm-up ended with status {wu.status}", 0,
                           nfev=wu.nfev)

    def fallback(note: str, mu: float = float("nan"), nfev: int = 0) -> SteadyStart:
        return SteadyStart(pmap.full(wu.x), transient_revs - wu.revs, "integrate", note, wu.revs, mu,
                           wu.nfev + nfev)

    if len(wu.sections) < APPROACH_REVS + 5 and not wu.settled:
        return fallback(f"warm-up of {wu.revs} revolutions too short to judge the approach")
    fp = find_fixed_point(pmap, wu.x, 1, method="chord", jacobian_rtol=CHORD_JACOBIAN_RTOL, exact_multipliers=False,
                          newton_fallback=False, max_iter=START_MAX_ITER)
    if not fp.converged:
        return fallback(f"shooting failed: {fp.message}", nfev=fp.nfev)
    mu = float(np.max(np.abs(fp.multipliers)))
    if not mu <= MAX_START_MULTIPLIER:
        return fallback(f"orbit not clearly stable (max |mu| {mu:.4f})", mu, fp.nfev)
    # the transient must be approaching this orbit (not another attractor): its distance to
    # the fixed point falls over the warm-up's last APPROACH_REVS revolutions
    dist = np.max(np.abs(pmap.difference(wu.sections, fp.x[None, :])), axis=1)
    late = float(dist[-5:].max())
    if wu.settled:
        ok = late <= 10.0 * float(np.max(np.abs(pmap.difference(wu.sections[-1], wu.sections[-2])))) / (1.0 - mu) \
            + 1e-6 if len(dist) > 1 else late <= 1e-6
    else:
        early = float(dist[-APPROACH_REVS - 5:-APPROACH_REVS].max())
        ok = late <= APPROACH_FACTOR * early
    if not ok:
        return fallback(f"warm-up does not approach the orbit (distance {late:.2e})", mu, fp.nfev)
    return SteadyStart(pmap.full(fp.x), 0, "shooting", "", wu.revs, mu, wu.nfev + fp.nfev)
