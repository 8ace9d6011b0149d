"""A stated running speed locked to the signal's own synchronous lines.

A plant engineer states the speed a control system shows or the machine's nominal one (3000 r/min for a two-pole
generator on a 50 Hz grid): it is often 0.1–0.5 % off the speed the shaft actually turned at during the record
(grid frequency, rounding, a slowly drifting turbine). Order analysis at a speed off by ε drifts by ε·N_revs
revolutions over the record at 1X (2εN_revs at 2X): negligible on 48 revolutions, but on a 4-second record at
3000 r/min (200 revolutions) a 0.4 % error turns the 2X phase through a whole turn and the order amplitudes
collapse. An analyst's order tracker therefore locks onto the running-speed line next to the stated speed; so
does :func:`locked_speed_hz`, within :data:`~._config.SPEED_LOCK_MAX_REL` of it, and only on lines that agree.
"""
from __future__ import annotations

import numpy as np

from . import _config as cfg
from ._lines import refine_line_hz
from ._spectrum import fast_length, hann_spectra

__all__ = ["locked_speed_hz"]


def _peak_near(power: np.ndarray, lo: int, hi: int) -> int | None:
    """The highest local maximum of ``power`` in bins ``lo … hi`` (None if there is none)."""
    lo, hi = max(lo, 1), min(hi, power.size - 2)
    if hi < lo:
        return None
    k = np.arange(lo, hi + 1)
    p = power[k]
    is_peak = (p >= power[k - 1]) & (p > power[k + 1])
    if not is_peak.any():
        return None
    return int(k[is_peak][np.argmax(p[is_peak])])


def locked_speed_hz(data: np.ndarray, fs: float, f_stated: float,
                    max_rel: float = cfg.SPEED_LOCK_MAX_REL) -> float | None:
    """The running speed (Hz) the record's synchronous lines show next to a stated one, or None.

    For each order h of :data:`~._config.SPEED_LOCK_ORDERS` the highest spectral peak (Hann window, channels'
    powers summed) within h·f_stated·(1 ± ``max_rel``) ± one bin that stands :data:`~._config.SPEED_LINE_MIN_SNR`
    times above the median spectrum (0.25–3.5 × f_stated) is refined (:func:`._lines.refine_line_hz`) and divided by
    h. The strongest such line gives the speed when at least :data:`~._config.SPEED_LOCK_MIN_LINES` orders show one
    and every other one agrees with it within
    :data:`~._config.SPEED_LOCK_AGREE_REL` (a line that does not — an oil whirl's 2nd harmonic inside the 1X's
    main lobe, say — is not synchronous, and the stated speed is kept) and it lies within ``max_rel`` of the
    stated speed.

    Parameters
    ----------
    data : ndarray, shape (n_channels, n_points)
        Probe displacements (any unit; means are removed).
    fs : float
        Sample rate, Hz.
    f_stated : float
        The stated running speed, Hz.
    max_rel : float
        How far (relative) the locked speed may lie from the stated one.

    Returns
    -------
    float or None
        The locked speed in Hz; None when no synchronous line stands out near the stated speed, the lines
        disagree, or the refined speed leaves the window (then the stated speed is the one to use).
    """
    n = data.shape[1]
    if n < 16 or not f_stated > 0:
        return None
    x, _, power = hann_spectra(data)
    df = fs / fast_length(n)
    band = power[max(int(0.25 * f_stated / df), 1):min(int(np.ceil(3.5 * f_stated / df)), power.size - 1) + 1]
    if band.size < 8:
        return None
    floor = float(np.median(band))
    lines: list[tuple[float, float]] = []          # (peak power, speed read from it, Hz)
    for h in cfg.SPEED_LOCK_ORDERS:
        if h * f_stated * (1.0 + max_rel) >= 0.45 * fs:
            break
        k = _peak_near(power, int(np.floor(h * f_stated * (1.0 - max_rel) / df)) - 1,
                       int(np.ceil(h * f_stated * (1.0 + max_rel) / df)) + 1)
        if k is None or not power[k] >= cfg.SPEED_LINE_MIN_SNR * floor:
            continue
        f_h = refine_line_hz(x, fs, k * df) / h
        if abs(f_h / f_stated - 1.0) <= max_rel:
            lines.append((float(power[k]), f_h))
    if len(lines) < cfg.SPEED_LOCK_MIN_LINES:
        return None
    f_best = max(lines)[1]
    if any(abs(f / f_best - 1.0) > cfg.SPEED_LOCK_AGREE_REL for _, f in lines):
        return None
    return f_best
