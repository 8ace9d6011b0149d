"""Order analysis: least-squares fit of the synchronous orders at the known shaft angle.

With the shaft angle θ(t) known (keyphasor or speed), each channel over a whole number of
revolutions is fitted as

    x(t) = c0 + Σ_{k=1..K} Re(C_k · exp(j k θ(t))) + r(t),

so ``C_k = A_k · exp(-j φ_k)`` with ``A_k`` the zero-to-peak amplitude and ``φ_k`` the phase
lag (degrees of the k-th order's own cycle from the θ = 0 reference to the positive peak:
``A_k cos(kθ − φ_k)``). This is exact for any speed, integer or not, with no leakage between
the fitted orders (for a noise-free synchronous signal it equals synchronous resampling followed
by a DFT). The fit is weighted by a Hann taper to keep non-synchronous lines out of the orders. ``r(t)`` — everything that is not a fitted order —
is the non-synchronous part.
"""
from __future__ import annotations

import threading

import numpy as np

from . import _config as cfg
from ._kernels import trig_rows
from ._spectrum import hann

__all__ = ["max_sync_order", "fit_orders", "forward_reverse"]


_local = threading.local()
#: samples per block of the order fit: bounds the scratch memory (basis + trig ≈ 10 MB for
#: K = 10) whatever the record length; records up to this long are fitted in one pass
BLOCK_SAMPLES = 32_768


def _workspace(name: str, shape: tuple[int, ...], dtype: type) -> np.ndarray:
    """A scratch array owned by the calling thread (a view of a buffer reused between calls)."""
    store = getattr(_local, "arrays", None)
    if store is None:
        store = _local.arrays = {}
    size = int(np.prod(shape))
    buf = store.get(name)
    if buf is None or buf.dtype != dtype or buf.size < size:
        buf = store[name] = np.empty(size, dtype=dtype)
    return buf[:size].reshape(shape)


def max_sync_order(min_samples_per_rev: float) -> int:
    """Highest order fitted: ``MAX_SYNC_ORDER`` or below 0.9 × Nyquist, whichever is lower."""
    return int(min(cfg.MAX_SYNC_ORDER, np.floor(0.45 * min_samples_per_rev)))


def _geometric_sum(n: int, step: np.ndarray) -> np.ndarray:
    """Σ_{i<n} e^{j·step·i} for each step (n where the step is a multiple of 2π)."""
    e = np.exp(1j * step)
    zero = np.abs(1 - e) < 1e-300
    den = np.where(zero, 1.0, 1 - e)
    return np.where(zero, n, (1 - np.exp(1j * step * n)) / den)


def _uniform_gram(n: int, step_rad: float, k_max: int, hann_taper: bool = True) -> np.ndarray:
    """``DᵀWD`` of the design [1, cos θ, sin θ, cos 2θ, sin 2θ, …] for θ_i = i·step, in closed form.

    ``W`` is the Hann taper ``w_i = ½ − ½ cos(2πi/(n−1))`` (or 1). With
    S(m) = Σ_i w_i e^{j m θ_i}, a sum of three geometric series,
    Σ w cos aθ cos bθ = ½ Re[S(a−b) + S(a+b)] and so on.
    """
    m = np.arange(2 * k_max + 1) * step_rad
    if hann_taper:
        beta = 2 * np.pi / (n - 1)
        s = 0.5 * _geometric_sum(n, m) - 0.25 * (_geometric_sum(n, m + beta) + _geometric_sum(n, m - beta))
    else:
        s = _geometric_sum(n, m)
    k = np.arange(1, k_max + 1)
    a, b = k[:, None], k[None, :]
    sp, sd = s[a + b], s[np.abs(a - b)]
    cc = 0.5 * (sp.real + sd.real)
    ss = 0.5 * (sd.real - sp.real)
    # Σ cos(aθ) sin(bθ) = ½ Σ [sin((a+b)θ) − sin((a−b)θ)]
    sd_signed = np.where(a >= b, sd.imag, -sd.imag)
    cs = 0.5 * (sp.imag - sd_signed)
    g = np.empty((2 * k_max + 1, 2 * k_max + 1))
    g[0, 0] = s[0].real
    g[0, 1::2] = g[1::2, 0] = s[k].real
    g[0, 2::2] = g[2::2, 0] = s[k].imag
    g[1::2, 1::2] = cc
    g[2::2, 2::2] = ss
    g[1::2, 2::2] = cs
    g[2::2, 1::2] = cs.T
    return g


def _trig_rows(theta_rad: np.ndarray, i0: int, i1: int, k_max: int,
               uniform_step_rad: float | None) -> np.ndarray:
    """Rows cos kθ, sin kθ (k = 1..K) for samples i0..i1, shape (2K, i1 − i0), in scratch memory."""
    nb = i1 - i0
    if uniform_step_rad is None:   # cos and sin (SIMD in NumPy) are ~1.6× faster than the complex exp
        e1 = np.empty(nb, dtype=np.complex128)
        np.cos(theta_rad[i0:i1], out=e1.real)
        np.sin(theta_rad[i0:i1], out=e1.imag)
    else:  # e^{jθ} in sub-blocks of 128: 2·√n complex exponentials instead of n
        sub = 128
        ns = -(-nb // sub)
        e1 = (np.exp(1j * uniform_step_rad * (i0 + sub * np.arange(ns)))[:, None]
              * np.exp(1j * uniform_step_rad * np.arange(sub))[None, :]).ravel()[:nb]
    trig = _workspace("trig", (2 * k_max, nb), np.float64)
    trig_rows(np.ascontiguousarray(e1), k_max, trig)       # rows cos kθ, sin kθ by e^{jkθ} = e^{j(k-1)θ}·e^{jθ}
    return trig


def fit_orders(theta_rad: np.ndarray, data: np.ndarray, max_order: int,
               uniform_step_rad: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hann-weighted least-squares fit of orders 1..``max_order`` plus a constant.

    The weights (a Hann taper over the analysed segment) change nothing for a signal made
    of the fitted orders — the fit is exact whatever the weights — but they suppress the
    leakage of non-synchronous lines (an oil whirl at 0.45X, say) into the order estimates
    from ~1/(π·distance in bins) to ~1/distance³; the price is a ≈ 1.22× (√1.5) larger noise
    standard error.

    Parameters
    ----------
    theta_rad : ndarray, shape (n,)
        Shaft angle of each sample.
    data : ndarray, shape (m, n)
        Channels (µm), one per row.
    max_order : int
    uniform_step_rad : float, optional
        When ``theta_rad[i] == i * uniform_step_rad`` (constant speed, θ = 0 at the first
        sample), the normal matrix is formed in closed form.

    Returns
    -------
    coeffs : ndarray, complex, shape (m, max_order)
        ``C_k`` (zero-to-peak, µm) for k = 1..max_order.
    mean : ndarray, shape (m,)
        Fitted constant (µm).
    residual : ndarray, shape (m, n)
        ``data`` minus the fit.
    """
    n = theta_rad.size
    k_max = int(max_order)
    m = data.shape[0]
    w = hann(n)
    blocks = [(i0, min(n, i0 + BLOCK_SAMPLES)) for i0 in range(0, n, BLOCK_SAMPLES)]
    general = uniform_step_rad is None
    gram = np.zeros((2 * k_max + 1, 2 * k_max + 1)) if general else \
        _uniform_gram(n, float(uniform_step_rad or 0.0), k_max)
    rhs = np.zeros((2 * k_max + 1, m))
    for i0, i1 in blocks:
        trig = _trig_rows(theta_rad, i0, i1, k_max, uniform_step_rad)
        wb = w[i0:i1]
        if general:
            wtrig = trig * wb
            gram[0, 0] += wb.sum()
            col = wtrig.sum(axis=1)
            gram[0, 1:] += col
            gram[1:, 0] += col
            gram[1:, 1:] += wtrig @ trig.T
        dw = np.multiply(data[:, i0:i1], wb, out=_workspace("weighted", (m, i1 - i0), np.float64))
        rhs[0] += dw.sum(axis=1)
        rhs[1:] += trig @ dw.T
    sol = np.linalg.solve(gram, rhs)       # (2K+1, m)
    residual = np.empty_like(data)
    for i0, i1 in blocks:
        # one block: the rows are still in the workspace; several: rebuild them
        trig = _trig_rows(theta_rad, i0, i1, k_max, uniform_step_rad) if len(blocks) > 1 else trig
        fit = np.matmul(sol[1:].T, trig, out=_workspace("fit", (m, i1 - i0), np.float64))  # contiguous: BLAS
        np.subtract(data[:, i0:i1], fit, out=residual[:, i0:i1])
    residual -= sol[0][:, None]
    coeffs = (sol[1::2] - 1j * sol[2::2]).T
    return coeffs, sol[0].copy(), residual


def forward_reverse(cx: np.ndarray, cy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Forward and reverse components of orders from the x and y coefficients.

    ``x + j y = Σ_k F_k e^{jkθ} + R_k e^{-jkθ}``: the +kX and −kX lines of the full
    spectrum of ``x + j y``. ``|F_k|`` and ``|R_k|`` are the radii (zero-to-peak) of the
    forward and reverse circles whose sum is the kX ellipse.
    """
    forward = 0.5 * (cx + 1j * cy)
    reverse = 0.5 * (np.conj(cx) + 1j * np.conj(cy))
    return forward, reverse
