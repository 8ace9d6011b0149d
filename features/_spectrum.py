"""Spectrum of the non-synchronous residual: sub-harmonic bands and noise level.

The synchronous orders are removed first (:mod:`._orders`), so a large 1X line cannot leak
into the sub-synchronous bands, whatever the window. The residual of each channel is
Hann-windowed and transformed; ``psd[k]`` is its one-sided mean-square per bin (µm²), so
summing it over a band gives the band's mean-square displacement.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["hann", "residual_psd", "band_power", "noise_rms"]


@lru_cache(maxsize=16)
def hann(n: int) -> np.ndarray:
    """Symmetric Hann window of length ``n`` (cached, read-only)."""
    w = np.hanning(n)
    w.flags.writeable = False
    return w


def residual_psd(residual: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided mean-square spectrum per bin of each row.

    Parameters
    ----------
    residual : ndarray, shape (m, n)

    Returns
    -------
    freqs_hz : ndarray, shape (n // 2 + 1,)
    psd_um2 : ndarray, shape (m, n // 2 + 1)
    """
    n = residual.shape[1]
    w = hann(n)
    spec = np.fft.rfft(residual * w, axis=-1)
    psd = (spec.real ** 2 + spec.imag ** 2) * (2.0 / (n * float(np.dot(w, w))))
    psd[:, 0] *= 0.5
    if n % 2 == 0:
        psd[:, -1] *= 0.5
    return np.fft.rfftfreq(n, 1.0 / fs), psd


def band_power(cum_psd: np.ndarray, orders: np.ndarray, lo: float, hi: float) -> float:
    """Mean-square in the bins whose centre order lies in ``[lo, hi)``.

    ``cum_psd`` is ``np.concatenate([[0], np.cumsum(psd)])`` of one spectrum and ``orders``
    the (ascending) order of each bin.
    """
    i0, i1 = np.searchsorted(orders, [lo, hi], side="left")
    return float(cum_psd[i1] - cum_psd[i0])


def noise_rms(psd: np.ndarray) -> np.ndarray:
    """Broadband noise RMS of each row from the median bin (robust to a few lines).

    For white noise of variance σ² each bin is (2σ²/n)·χ²₂/2, whose median is ln 2 times its
    mean, so σ² = n_bins·median/ln 2. The median is taken over every 4th bin (speed).
    """
    n_bins = psd.shape[1] - 1
    return np.sqrt(n_bins * np.median(psd[:, 1::4], axis=1) / np.log(2.0))
