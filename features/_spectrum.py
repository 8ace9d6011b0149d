"""Spectrum of the non-synchronous residual: sub-harmonic bands and noise level.

The synchronous orders are removed first (:mod:`._orders`), so a large 1X line cannot leak
into the sub-synchronous bands, whatever the window. The residual of each channel is
Hann-windowed and transformed; ``psd[k]`` is its one-sided mean-square per bin (µm²), so
summing it over a band gives the band's mean-square displacement.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.fft as _fft

from ._kernels import kth_smallest_rows, power_spectrum

__all__ = ["fast_length", "hann", "residual_psd", "band_power", "noise_rms"]


@lru_cache(maxsize=64)
def fast_length(n: int) -> int:
    """Smallest FFT length ≥ n with small prime factors (the record is zero-padded to it).

    An analysed segment of a whole number of revolutions has an arbitrary length (16 037 =
    7 × 2291, say), for which the FFT is ~4× slower than for a 5-smooth length.
    """
    from scipy.fft import next_fast_len

    return int(next_fast_len(int(n), real=True))


@lru_cache(maxsize=16)
def hann(n: int) -> np.ndarray:
    """Symmetric Hann window of length ``n`` (cached, read-only)."""
    w = np.hanning(n)
    w.flags.writeable = False
    return w


def hann_spectra(data: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(channels less their means, their Hann-windowed spectra at :func:`fast_length`, the channels' powers
    summed) of a multichannel record (n_channels, n_points): what the running-speed estimate and the lock of a
    given speed (``_speed``, ``_speed_lock``) search for lines."""
    n = data.shape[1]
    x = data - data.mean(axis=1)[:, None]
    spec = np.fft.rfft(x * hann(n), n=fast_length(n), axis=-1)
    return x, spec, np.sum(spec.real ** 2 + spec.imag ** 2, axis=0)


def residual_psd(residual: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided mean-square spectrum per bin of each row (zero-padded to a fast FFT length).

    Summing ``psd`` over all bins gives the window-weighted mean square of the row, with or
    without the padding (Parseval: Σ|X_k|² = n_fft · Σ(x·w)²).

    Parameters
    ----------
    residual : ndarray, shape (m, n)

    Returns
    -------
    freqs_hz : ndarray, shape (n // 2 + 1,)
    psd_um2 : ndarray, shape (m, n // 2 + 1)
    """
    n = residual.shape[1]
    n_fft = fast_length(n)
    w = hann(n)
    # scipy's pocketfft, one thread: ~30 % faster than numpy.fft on 8 × 16 k
    spec = _fft.rfft(residual * w, n=n_fft, axis=-1, workers=1)
    psd = power_spectrum(spec, 2.0 / (n_fft * float(np.dot(w, w))), n_fft % 2 == 0)
    return _rfftfreq(n_fft, float(fs)), psd


@lru_cache(maxsize=16)
def _rfftfreq(n_fft: int, fs: float) -> np.ndarray:
    f = np.fft.rfftfreq(n_fft, 1.0 / fs)
    f.flags.writeable = False
    return f


def band_power(cum_psd: np.ndarray, orders: np.ndarray, lo: float, hi: float) -> float:
    """Mean-square in the bins whose centre order lies in ``[lo, hi)``.

    ``cum_psd`` is ``np.concatenate([[0], np.cumsum(psd)])`` of one spectrum and ``orders``
    the (ascending) order of each bin.
    """
    i0, i1 = np.searchsorted(orders, [lo, hi], side="left")
    return float(cum_psd[i1] - cum_psd[i0])


def noise_rms(psd: np.ndarray) -> np.ndarray:
    """Broadband noise RMS of each row from the median bin (robust to a few lines).

    For white noise of variance σ² each bin is (2σ²/n_fft)·χ²₂/2, whose median is ln 2 times
    its mean, so σ² = (n_fft/2)·median/ln 2. The median is taken over every 4th bin (speed).
    """
    n_bins = psd.shape[1] - 1
    sample = psd[:, 1::4]
    mid = sample.shape[1] // 2
    median = kth_smallest_rows(sample, mid)                 # upper median; bias O(1/n_bins)
    return np.sqrt(n_bins * median / np.log(2.0))


def line_noise_amplitude(psd: np.ndarray, orders_axis: np.ndarray, n_seg: int, orders: tuple[int, ...],
                         half_width: float) -> np.ndarray:
    """Noise-equivalent zero-to-peak amplitude of the least-squares fit of each order, per row.

    For white noise of variance σ² the fitted complex coefficient of an order over ``n_seg``
    samples (whole revolutions) errs by ``E|ΔC|² = 4σ²/n_seg``. The local noise level is the
    residual spectrum's mean bin power ``P = 2σ²/n_fft`` around the order, estimated as its
    median over ``[k − half_width, k + half_width]`` divided by ln 2 (χ²₂ bins; robust to a
    few lines), so the noise-equivalent amplitude is ``√(2·P·n_fft / n_seg)``.

    Parameters
    ----------
    psd : ndarray, shape (m, n_fft // 2 + 1)
        Residual power spectrum (:func:`residual_psd`), µm² per bin.
    orders_axis : ndarray
        Order of each bin (frequency over running speed), ascending.
    n_seg : int
        Samples the orders were fitted over.
    orders : tuple of int
    half_width : float
        Half-width of the band, orders.

    Returns
    -------
    ndarray, shape (m, len(orders))
        µm, zero-to-peak; NaN where the band holds fewer than 3 bins.
    """
    n_fft = 2 * (psd.shape[1] - 1)
    out = np.full((psd.shape[0], len(orders)), np.nan)
    for j, k in enumerate(orders):
        i0, i1 = np.searchsorted(orders_axis, [k - half_width, k + half_width], side="left")
        if i1 - i0 >= 3:
            p_mean = np.median(psd[:, i0:i1], axis=1) / np.log(2.0)
            out[:, j] = np.sqrt(2.0 * p_mean * n_fft / n_seg)
    return out
