"""Motion type from a Poincaré set (and optionally the largest Lyapunov exponent).

NumPy only, so that the features package classifies a recording's motion without loading the analysis sweeps
(``rotordiag.simulator.analysis`` re-exports it).

Rules (MODEL.md §8), applied in this order:

1. **period-n** — the smallest ``n`` in ``1..max_period`` for which every point
   returns to within ``tol`` of itself after ``n`` sections,
   ``max_k ||P[k+n] - P[k]|| <= tol`` with ``tol = period_rtol * orbit_size``.
   ``orbit_size`` is the size of the *orbit* (e.g. the peak-to-peak of the
   recorded waveform), not of the Poincaré set, because a period-1 set has no
   size of its own.  When not given it defaults to the larger of the set's
   peak-to-peak extent and its RMS distance from the origin — right for journal
   displacements measured from the bearing centre, wrong for AC-coupled
   signals (pass ``orbit_size`` then).  At least ``min_repeats`` repetitions
   of the candidate cycle must be present.
2. Otherwise the motion is non-periodic (or of period > ``max_period``):
   * with an LLE (per section interval, i.e. per revolution):
     ``lle > noise`` → **chaotic**; ``|lle| <= noise`` → **quasi-periodic**;
     ``lle < -noise`` → **unresolved** (a stable orbit of period > ``max_period``,
     or a transient that has not died out).  ``noise = max(lle_noise,
     3 * stderr)`` when a ``simulator.analysis.LyapunovResult`` is passed.
   * without an LLE, from the data: the mean logarithmic divergence rate of
     nearest neighbours in the set over ``1..k`` sections (a one-shot,
     Rosenstein-style estimate, :func:`poincare_divergence_rate`):
     ``> divergence_threshold`` → **chaotic**, else **quasi-periodic**.
     This needs a section of dimension ≥ 2 for a torus (a closed curve projected
     onto one coordinate folds over itself); pass several coordinates (e.g. X
     and Y of one or more journals) or use ``delay_embedding``.

Default thresholds (module constants): ``PERIOD_RTOL = 1e-3``,
``LLE_NOISE_PER_INTERVAL = 0.01``, ``DIVERGENCE_THRESHOLD = 0.15`` per section.
``LLE_NOISE_PER_INTERVAL`` is above the finite-time scatter of a torus' zero
exponent over a few hundred revolutions (|LLE| ≲ 0.003 on the test torus; the
rotor's whirl gives |LLE| ≲ 0.03 with 100 revolutions, which the 3 × standard
error term absorbs). Periodic rotor motion contracts at −0.2 to −0.01 per
revolution on the default plant and weaker still right at a bifurcation
(−0.007 at the whirl threshold), but periodic sets are decided by the period
test first, so the LLE threshold only splits non-periodic sets. The divergence
threshold sits between a torus' ≈ 0 and the Hénon map's 0.42 (this one-shot
estimate reads 0.35–0.42 on 128–512 points) and the logistic map's ln 2.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "MotionType",
    "classify_motion",
    "detect_period",
    "poincare_divergence_rate",
    "PERIOD_RTOL",
    "MAX_PERIOD",
    "LLE_NOISE_PER_INTERVAL",
    "DIVERGENCE_THRESHOLD",
]

#: relative tolerance of the period test (fraction of the orbit size)
PERIOD_RTOL = 1e-3
#: longest period tested
MAX_PERIOD = 16
#: |LLE| per interval below which an exponent is taken as zero
LLE_NOISE_PER_INTERVAL = 0.01
#: neighbour divergence rate per section above which a non-periodic set is chaotic
DIVERGENCE_THRESHOLD = 0.15
#: how many times a candidate cycle must be seen
MIN_REPEATS = 3

KINDS = ("period-n", "quasi-periodic", "chaotic", "unresolved")


@dataclass(frozen=True)
class MotionType:
    """Result of :func:`classify_motion`.

    Attributes
    ----------
    kind : str
        ``"period-n"``, ``"quasi-periodic"``, ``"chaotic"`` or ``"unresolved"``.
    period : int or None
        ``n`` for ``kind == "period-n"``, else None.
    evidence : str
        What decided it (the distances, exponent or rate and the thresholds).
    """

    kind: str
    period: int | None = None
    evidence: str = ""

    @property
    def label(self) -> str:
        """Short label: ``"period-3"``, ``"quasi-periodic"``, ``"chaotic"``, ``"unresolved"``."""
        return f"period-{self.period}" if self.kind == "period-n" else self.kind

    def __str__(self) -> str:  # pragma: no cover - trivial
        return self.label


def _as_points(poincare_points: object, delay_embedding: int = 1) -> np.ndarray:
    pts = np.asarray(poincare_points, dtype=float)
    if pts.ndim == 0 or pts.shape[0] == 0:
        raise ValueError("poincare_points must be an array of shape (n_sections, ...) with n_sections >= 1")
    pts = pts.reshape(pts.shape[0], -1)
    if not np.all(np.isfinite(pts)):
        raise ValueError("poincare_points contains NaN or inf (a failed or diverged run?)")
    if isinstance(delay_embedding, bool) or int(delay_embedding) != delay_embedding or delay_embedding < 1:
        raise ValueError(f"delay_embedding must be an integer >= 1, got {delay_embedding!r}")
    m = int(delay_embedding)
    if m > 1:
        if pts.shape[0] <= m:
            raise ValueError(f"need more than delay_embedding={m} points, got {pts.shape[0]}")
        pts = np.hstack([pts[i: pts.shape[0] - m + 1 + i] for i in range(m)])
    return pts


def detect_period(
    poincare_points: np.ndarray,
    *,
    orbit_size: float | None = None,
    period_rtol: float = PERIOD_RTOL,
    max_period: int = MAX_PERIOD,
    min_repeats: int = MIN_REPEATS,
) -> tuple[int | None, np.ndarray, float]:
    """Smallest period of a Poincaré set, or None.

    Parameters
    ----------
    poincare_points : array_like, shape (n_sections, ...)
        Successive section points (any trailing shape; flattened per section).
    orbit_size, period_rtol, max_period, min_repeats
        See :func:`classify_motion`.

    Returns
    -------
    period : int or None
    return_distances : ndarray, shape (max_period_tested,)
        ``max_k ||P[k+n] - P[k]||`` for n = 1, 2, ...
    tol : float
        The absolute tolerance used.
    """
    pts = _as_points(poincare_points)
    if not (np.isfinite(period_rtol) and period_rtol > 0):
        raise ValueError(f"period_rtol must be a positive fraction, got {period_rtol!r}")
    if int(max_period) != max_period or max_period < 1:
        raise ValueError(f"max_period must be an integer >= 1, got {max_period!r}")
    if int(min_repeats) != min_repeats or min_repeats < 2:
        raise ValueError(f"min_repeats must be an integer >= 2, got {min_repeats!r}")
    if orbit_size is None:
        spread = float(np.max(np.ptp(pts, axis=0)))
        rms = float(np.sqrt(np.mean(np.sum(pts ** 2, axis=1))))
        size = max(spread, rms)
    else:
        size = float(orbit_size)
        if not (np.isfinite(size) and size >= 0):
            raise ValueError(f"orbit_size must be a finite size >= 0, got {orbit_size!r}")
    tol = period_rtol * size
    n_pts = pts.shape[0]
    n_max = min(int(max_period), n_pts // int(min_repeats))
    if n_max < 1:
        raise ValueError(f"need at least min_repeats={min_repeats} Poincaré points, got {n_pts}")
    distances = np.empty(n_max)
    found = None
    for n in range(1, n_max + 1):
        distances[n - 1] = float(np.max(np.linalg.norm(pts[n:] - pts[:-n], axis=1)))
        if found is None and distances[n - 1] <= tol:
            found = n
    return found, distances, tol


def poincare_divergence_rate(
    poincare_points: np.ndarray, *, max_steps: int = 4, delay_embedding: int = 1
) -> float:
    """Mean logarithmic divergence of nearest neighbours in a Poincaré set, per section.

    For every point ``i`` (among the first ``n - max_steps``) take its nearest
    neighbour ``j`` in the set; ``s_k`` is the mean of
    ``log(||P[i+k] - P[j+k]|| / ||P[i] - P[j]||)``.  Returns the least-squares
    slope of ``s_k`` against ``k = 1..max_steps`` through the origin.  ≈ the LLE
    for chaotic sets (biased low by saturation on few points), ≈ 0 for
    invariant closed curves (tori) and NaN if no usable neighbour pair exists.
    """
    pts = _as_points(poincare_points, delay_embedding)
    if int(max_steps) != max_steps or max_steps < 1:
        raise ValueError(f"max_steps must be an integer >= 1, got {max_steps!r}")
    k_max = int(max_steps)
    n_base = pts.shape[0] - k_max
    if n_base < 3:
        raise ValueError(f"need at least {k_max + 3} Poincaré points, got {pts.shape[0]}")
    base = pts[:n_base]
    d2 = np.sum((base[:, None, :] - base[None, :, :]) ** 2, axis=2)
    np.fill_diagonal(d2, np.inf)
    j = np.argmin(d2, axis=1)
    d0 = np.sqrt(d2[np.arange(n_base), j])
    ok = d0 > 0
    if not np.any(ok):
        return float("nan")
    i = np.arange(n_base)[ok]
    j = j[ok]
    d0 = d0[ok]
    ks = np.arange(1, k_max + 1)
    s = np.empty(k_max)
    for k in ks:
        dk = np.linalg.norm(pts[i + k] - pts[j + k], axis=1)
        good = dk > 0
        s[k - 1] = np.mean(np.log(dk[good] / d0[good])) if np.any(good) else -np.inf
    if not np.all(np.isfinite(s)):
        return float("nan")
    return float(np.sum(ks * s) / np.sum(ks * ks))


def classify_motion(
    poincare_points: np.ndarray,
    lle: Any = None,
    *,
    orbit_size: float | None = None,
    period_rtol: float = PERIOD_RTOL,
    max_period: int = MAX_PERIOD,
    lle_noise: float = LLE_NOISE_PER_INTERVAL,
    divergence_threshold: float = DIVERGENCE_THRESHOLD,
    delay_embedding: int = 1,
    min_repeats: int = MIN_REPEATS,
) -> MotionType:
    """Classify a steady-state motion as period-n, quasi-periodic or chaotic.

    Parameters
    ----------
    poincare_points : array_like, shape (n_sections, ...)
        Once-per-revolution (once-per-forcing-period) samples of the steady
        state, oldest first; any trailing shape, e.g. ``(n, 6, 2)`` for all
        nodes' x/y or ``(n,)`` for one coordinate.
    lle : float or LyapunovResult, optional
        Largest Lyapunov exponent **per section interval** (per revolution).
    orbit_size : float, optional
        Scale of the orbit for the period tolerance (same units as the points);
        see the module docstring for the default.
    period_rtol : float
        Period tolerance as a fraction of ``orbit_size``.
    max_period : int
        Longest period looked for (MODEL.md: 16).
    lle_noise : float
        Exponents with ``|lle| <= lle_noise`` count as zero.
    divergence_threshold : float
        Threshold on :func:`poincare_divergence_rate` when no LLE is given.
    delay_embedding : int
        For the divergence test without LLE: number of successive sections
        stacked per point (use 2–3 when only one coordinate is available).
    min_repeats : int
        Minimum number of repetitions of a cycle for it to count.

    Returns
    -------
    MotionType
    """
    if not (np.isfinite(lle_noise) and lle_noise >= 0):
        raise ValueError(f"lle_noise must be >= 0, got {lle_noise!r}")
    period, distances, tol = detect_period(
        poincare_points, orbit_size=orbit_size, period_rtol=period_rtol,
        max_period=max_period, min_repeats=min_repeats)
    if period is not None:
        return MotionType("period-n", period,
                          f"return distance {distances[period - 1]:.3g} <= tol {tol:.3g} after {period} sections")
    closest = int(np.argmin(distances)) + 1
    prefix = f"no period <= {distances.size} (closest n={closest}: {distances[closest - 1]:.3g} > tol {tol:.3g}); "
    if lle is not None:
        if hasattr(lle, "lle_per_interval"):           # a simulator.analysis.LyapunovResult
            value = lle.lle_per_interval
            noise = max(lle_noise, 3 * lle.stderr_per_interval) if np.isfinite(lle.stderr_per_interval) \
                else lle_noise
        else:
            value = float(lle)
            noise = lle_noise
        if not np.isfinite(value):
            raise ValueError(f"lle must be finite, got {value!r}")
        if value > noise:
            return MotionType("chaotic", None, prefix + f"LLE {value:.4g} > noise {noise:.3g}")
        if value >= -noise:
            return MotionType("quasi-periodic", None, prefix + f"|LLE| {abs(value):.3g} <= noise {noise:.3g}")
        return MotionType("unresolved", None,
                          prefix + f"LLE {value:.4g} < -noise {noise:.3g}: period > {distances.size} "
                          "or transient not settled")
    rate = poincare_divergence_rate(poincare_points, delay_embedding=delay_embedding)
    if not np.isfinite(rate):
        return MotionType("unresolved", None, prefix + "no usable neighbour pairs for the divergence test")
    if rate > divergence_threshold:
        return MotionType("chaotic", None,
                          prefix + f"neighbour divergence {rate:.3g}/section > {divergence_threshold:.3g}")
    return MotionType("quasi-periodic", None,
                      prefix + f"neighbour divergence {rate:.3g}/section <= {divergence_threshold:.3g}")
