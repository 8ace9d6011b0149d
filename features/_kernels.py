"""Compiled inner loops of the feature extractor (numba, cached on disk).

Each kernel does the same floating-point operations, in the same order, as the NumPy
expression it replaces (noted on each), so features are unchanged to rounding (~1e-15);
what it saves is the temporaries and the passes over memory. ``fastmath`` stays off so
that no operation is reordered or contracted.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

_OPTS: dict[str, Any] = dict(cache=True, nogil=True, fastmath=False, error_model="numpy")

__all__ = ["trig_rows", "coarse_diameter", "kth_smallest_rows", "power_spectrum"]


@njit(**_OPTS)
def trig_rows(e1: np.ndarray, k_max: int, out: np.ndarray) -> None:  # pragma: no cover - compiled
    """``out[2k-2] = Re e1^k``, ``out[2k-1] = Im e1^k`` for k = 1..k_max (``out`` C-contiguous), the
    powers by repeated multiplication ``e^{jkθ} = e^{j(k-1)θ} · e^{jθ}`` (as NumPy's
    ``basis[k] = basis[k-1] * e1``, without the fused multiply-add NumPy's SIMD loop may use:
    the rows can differ from it in the last bit).

    Order by order over whole rows, in real arithmetic: the inner loop vectorises, and only four
    rows are touched at a time (20 rows a power of two apart alias in the L1 cache: a per-sample
    loop over the orders ran 8× slower for 16 384 samples than for 16 352).
    """
    n = e1.size
    c = out[0]
    s = out[1]
    for i in range(n):
        c[i] = e1[i].real
        s[i] = e1[i].imag
    for k in range(1, k_max):
        a = out[2 * k - 2]
        b = out[2 * k - 1]
        re = out[2 * k]
        im = out[2 * k + 1]
        for i in range(n):
            x = a[i]
            y = b[i]
            u = c[i]
            v = s[i]
            re[i] = x * u - y * v
            im[i] = x * v + y * u


@njit(**_OPTS)
def coarse_diameter(xs: np.ndarray, ys: np.ndarray, argmax: np.ndarray, d2max: np.ndarray) -> None:  # pragma: no cover
    """Largest squared pairwise distance of each row's points and the first (row-major) pair
    attaining it: ``d2 = (xi − xj)² + (yi − yj)²``, ``flat = d2.reshape(nb, -1).argmax(1)``.

    ``d2`` is symmetric bit for bit (``(a − b)² == (b − a)²``), so the first maximum in row-major
    order lies on or above the diagonal and only that triangle is scanned.
    """
    nb, m = xs.shape
    for b in range(nb):
        best = -np.inf
        arg = 0
        for i in range(m):
            xi = xs[b, i]
            yi = ys[b, i]
            for j in range(i, m):
                dx = xi - xs[b, j]
                dy = yi - ys[b, j]
                d = dx * dx + dy * dy
                if d > best:
                    best = d
                    arg = i * m + j
                elif np.isnan(d):           # NumPy's argmax / max stop at the first NaN
                    best = d
                    arg = i * m + j
                    break
            if np.isnan(best):
                break
        argmax[b] = arg
        d2max[b] = best


@njit(**_OPTS)
def kth_smallest_rows(a: np.ndarray, k: int) -> np.ndarray:  # pragma: no cover - compiled
    """``np.partition(a, k, axis=1)[:, k]``: the k-th smallest of each row (NaN sorts last)."""
    m, n = a.shape
    out = np.empty(m)
    buf = np.empty(n)
    for r in range(m):
        has_nan = False
        for i in range(n):
            buf[i] = a[r, i]
            if np.isnan(buf[i]):
                has_nan = True
        if has_nan:
            out[r] = np.sort(buf)[k]
            continue
        lo, hi = 0, n - 1
        while lo < hi:
            # median-of-three pivot, Hoare partition
            mid = (lo + hi) // 2
            x, y, z = buf[lo], buf[mid], buf[hi]
            if x < y:
                pivot = y if y < z else (z if x < z else x)
            else:
                pivot = x if x < z else (z if y < z else y)
            i, j = lo, hi
            while i <= j:
                while buf[i] < pivot:
                    i += 1
                while buf[j] > pivot:
                    j -= 1
                if i <= j:
                    t = buf[i]
                    buf[i] = buf[j]
                    buf[j] = t
                    i += 1
                    j -= 1
            if k <= j:
                hi = j
            elif k >= i:
                lo = i
            else:
                break
        out[r] = buf[k]
    return out


@njit(**_OPTS)
def power_spectrum(spec: np.ndarray, scale: float, even: bool) -> np.ndarray:  # pragma: no cover - compiled
    """``(re² + im²) · scale`` of each bin, the first (and, for an even FFT length, the last)
    bin halved: the one-sided mean-square per bin of :func:`features._spectrum.residual_psd`."""
    m, nf = spec.shape
    out = np.empty((m, nf))
    for r in range(m):
        for i in range(nf):
            re = spec[r, i].real
            im = spec[r, i].imag
            out[r, i] = (re * re + im * im) * scale
        out[r, 0] *= 0.5
        if even:
            out[r, nf - 1] *= 0.5
    return out
