"""Spectral lines of a multichannel record: peaks, genuine lines, modulation sidebands, refined frequencies and how
circular the orbits are at a line — the primitives of the running-speed estimate (:mod:`._speed`)."""
from __future__ import annotations

import numpy as np

from . import _config as cfg
from ._spectrum import fast_length, hann

__all__ = ["refine_line_hz", "running_speed_line", "LINE_CLASSES"]


def _hann_amplitude_at(power: np.ndarray, f: float, df: float) -> float:
    k = int(round(f / df))
    if k < 1 or k >= power.size - 1:
        return 0.0
    return float(np.sqrt(np.max(power[k - 1:k + 2])))


def _lines_at(power: np.ndarray, kk: np.ndarray, level: float, sidebands: np.ndarray | None = None) -> np.ndarray:
    """Which bins ``kk`` hold a spectral line: a local maximum (the right one of a tie) at or above ``level``
    that is not a modulation sideband (``sidebands``, from :func:`_modulation_sidebands`)."""
    ok = (power[kk] >= power[kk - 1]) & (power[kk] > power[kk + 1]) & (power[kk] >= level)
    return ok if sidebands is None else ok & ~sidebands[kk]


def _modulation_sidebands(power: np.ndarray, df: float, level: float) -> np.ndarray:
    """Bins of the spectral peaks that are modulation sidebands of a stronger line: ``(power.size,)`` bool.

    A running speed that wanders (Ω(1 + ε sin 2πf_m t): a governor, the grid) phase-modulates every
    order kΩ into a carrier with sidebands at kΩ ± j f_m, pairs of equal amplitude, growing with k; on
    a long record they are resolved, and a family of them (kΩ − f_m …) would pass for an independent
    running speed, or for a whirl's combination lines. A peak at g is a sideband of a line c within
    ``SPEED_SIDEBAND_MAX_REL`` × c of it (and ``SPEED_SIDEBAND_MIN_BINS`` away: closer, a pair is not resolved
    from the line's main lobe) when c
    stands ``SPEED_SIDEBAND_MIN_DROP`` times above the pair g, 2c − g and the pair's powers (each the
    largest within a bin: a twin beside a strong line may ride on its skirt, no peak of its own) lie
    within ``SPEED_SIDEBAND_MIRROR`` times of each other. The comb c ± j·d (d = |g − c|, j = 2, 3, …) is
    followed while its pairs pass the same test. Peaks are those above ``level``; lines are tried as
    carriers strongest first, and a sideband is no carrier. A whirl's combination line beside its 2nd
    harmonic (Ω = 2ω + d) has no such twin (4ω − Ω is a higher-order combination, far weaker); the
    mirror pairs kω, 2Ω − kω of a whip about the 1X lie further out than ``SPEED_SIDEBAND_MAX_REL``.
    """
    kk = np.arange(2, power.size - 1)
    is_pk = np.zeros(power.size, dtype=bool)
    is_pk[kk] = _lines_at(power, kk, level)
    pk = np.flatnonzero(is_pk)
    side = np.zeros(power.size, dtype=bool)

    def pair(c: int, d: int, half: int) -> tuple[float, float] | None:
        lo, hi = c - d, c + d
        if lo - half < 1 or hi + half + 1 > power.size:
            return None
        return float(np.max(power[lo - half:lo + half + 1])), float(np.max(power[hi - half:hi + half + 1]))

    # bounded work on any spectrum (a hostile upload can make every other bin a peak): the strongest lines
    # as carriers, and for each the nearest few peaks as the first pair
    for c in pk[np.argsort(-power[pk], kind="stable")][:cfg.SPEED_SIDEBAND_MAX_CARRIERS]:
        if side[c]:
            continue
        span = int(cfg.SPEED_SIDEBAND_MAX_REL * c)
        near = pk[np.searchsorted(pk, c - span):np.searchsorted(pk, c + span, side="right")]
        near = near[np.abs(near - c) >= cfg.SPEED_SIDEBAND_MIN_BINS]
        for g in near[np.argsort(np.abs(near - c), kind="stable")][:cfg.SPEED_SIDEBAND_MAX_TRIES]:
            if side[g]:
                continue
            d = int(abs(g - c))
            for j in range(1, cfg.SPEED_SIDEBAND_MAX_ORDER + 1):
                half = (j + 1) // 2                     # the spacing's rounding error grows with j
                p = pair(c, j * d, half)
                if p is None or power[c] < cfg.SPEED_SIDEBAND_MIN_DROP * max(p) or \
                        not 1 / cfg.SPEED_SIDEBAND_MIRROR <= p[0] / p[1] <= cfg.SPEED_SIDEBAND_MIRROR:
                    break
                found = False
                for b in (c - j * d, c + j * d):
                    hit = is_pk[b - half:b + half + 1]
                    side[b - half:b + half + 1] |= hit
                    found |= bool(hit.any())
                if not found:
                    break
    return side


def _line_amplitude(power: np.ndarray, logp: np.ndarray, f: float, df: float, level: float,
                    sidebands: np.ndarray, tol_bins: float = 0.5) -> float:
    """Amplitude (√power) of a genuine spectral line at ``f``, else 0.

    Genuine: a local maximum of the spectrum within ±1 bin of ``f`` whose interpolated centre
    lies within ``tol_bins`` (half a bin) of ``f`` and whose power reaches ``level``. The skirt of a strong
    neighbouring line (e.g. oil whirl at 0.47X next to 0.5X) is not a line, nor is a modulation sideband
    (``sidebands``, from :func:`_modulation_sidebands`).
    """
    k0 = int(round(f / df))
    if k0 < 2 or k0 >= power.size - 2:
        return 0.0
    k = k0 - 1 + int(np.argmax(power[k0 - 1:k0 + 2]))
    if not (power[k] >= power[k - 1] and power[k] > power[k + 1]) or power[k] < level:
        return 0.0
    if sidebands[k]:
        return 0.0
    den = logp[k - 1] - 2 * logp[k] + logp[k + 1]
    delta = 0.5 * (logp[k - 1] - logp[k + 1]) / den if den < 0 else 0.0
    if abs(k + delta - f / df) > tol_bins:
        return 0.0
    return float(np.sqrt(power[k]))


def _non_harmonic_lines(power: np.ndarray, peak_idx: np.ndarray, df: float, f1: float, level: float) -> list[float]:
    """Frequencies (Hz, strongest first) of spectral peaks at or above ``level`` that are not
    within one bin of an integer multiple of ``f1`` (nor below 0.05 × ``f1``, slow drift)."""
    out = []
    for k in peak_idx:                              # already strongest first
        if power[k] < level:
            continue
        f = k * df
        m = round(f / f1)
        if f < 0.05 * f1 or (m >= 1 and abs(f - m * f1) <= 1.0 * df + 1e-3 * f):
            continue
        out.append(float(f))
    return out


def _hann_kernel(theta: np.ndarray, n: int) -> np.ndarray:
    """DTFT of the symmetric Hann window of length ``n`` at angular frequencies ``theta`` (rad/sample):
    Σ w_k e^{-jθk}, from the Dirichlet kernel (so a windowed line at ω shows as ``_hann_kernel(ν − ω)``)."""
    def dirichlet(t: np.ndarray) -> np.ndarray:
        s = np.sin(t / 2)
        small = np.abs(s) < 1e-12
        return np.exp(-0.5j * t * (n - 1)) * np.where(small, float(n), np.sin(n * t / 2) / np.where(small, 1.0, s))

    a = 2 * np.pi / (n - 1)
    return 0.5 * dirichlet(theta) - 0.25 * dirichlet(theta - a) - 0.25 * dirichlet(theta + a)


def _local_peak_ratio(power: np.ndarray, f: float, df: float, floor: float, tol_bins: float,
                      sidebands: np.ndarray) -> float:
    """Power of the highest local maximum of ``power`` within ``tol_bins`` of ``f``, over ``floor``
    (0 when there is none)."""
    k0 = int(round(f / df))
    r = int(np.ceil(tol_bins))
    lo, hi = max(k0 - r, 1), min(k0 + r, power.size - 2)
    best = 0.0
    for k in range(lo, hi + 1):
        if (abs(k - f / df) <= tol_bins and power[k] >= power[k - 1] and power[k] > power[k + 1]
                and not sidebands[k]):
            best = max(best, float(power[k]) / floor)
    return best


def refine_line_hz(data: np.ndarray, fs: float, f0: float, iterations: int = cfg.SPEED_REFINE_ITERATIONS) -> float:
    """Refine the frequency of a spectral line near ``f0`` (Hz) by the phase-difference method.

    The record (columns of ``data``, mean removed) is split in two halves; each is demodulated
    at the current estimate with a Hann window; the phase advance of the line from the first
    half to the second, summed coherently over the channels, corrects the frequency. Converges
    from within about one FFT bin of the full record.
    """
    n = data.shape[1]
    h = n // 2
    w = hann(h)
    x1 = data[:, :h]
    x2 = data[:, h:2 * h]
    f = float(f0)
    sub = 128
    ns = -(-h // sub)
    coarse_i = sub * np.arange(ns)
    fine_i = np.arange(sub)
    for _ in range(iterations):
        step = -2 * np.pi * f / fs
        # w·e^{-j2πf·i/fs} from 2·√h exponentials (i = 128a + b), as a real (h, 2) array so that
        # the products with the real channels are real matrix products
        e = (np.exp(1j * step * coarse_i)[:, None] * np.exp(1j * step * fine_i)[None, :]).ravel()[:h]
        e *= w
        ev = e.view(np.float64).reshape(h, 2)
        p1 = x1 @ ev
        p2 = x2 @ ev
        c1 = p1[:, 0] + 1j * p1[:, 1]
        c2 = (p2[:, 0] + 1j * p2[:, 1]) * np.exp(1j * step * h)
        dphi = float(np.angle(np.vdot(c1, c2)))
        f = f + dphi * fs / (2 * np.pi * h)
    return f


def _circular_fraction_at(spec: np.ndarray, f: float, df: float) -> float:
    """:func:`_circular_fraction` at the FFT bin nearest ``f`` (Hz; bin width ``df``)."""
    return _circular_fraction(spec, int(round(f / df)))


def _circular_fraction(spec: np.ndarray, k: int) -> float:
    """How far from a circle the orbits are at FFT bin ``k``: the median over bearings of min(F, B) / max(F, B).

    ``spec`` holds the Hann spectra of the x, y rows of each bearing in turn (as
    ``_speed.estimate_speed_hz`` receives them); F and B are the magnitudes of the forward and backward
    circular components (x ∓ iy) of the line. 0 for perfectly circular orbits in either direction,
    1 for straight lines; NaN without an x/y pair.
    """
    n_b = spec.shape[0] // 2
    if n_b == 0:
        return float("nan")
    x, y = spec[0:2 * n_b:2, k], spec[1:2 * n_b:2, k]
    fwd, bwd = np.abs(x - 1j * y), np.abs(x + 1j * y)
    big = np.maximum(fwd, bwd)
    if not np.any(big > 0):
        return float("nan")
    return float(np.median(np.minimum(fwd, bwd)[big > 0] / big[big > 0]))


#: how the running speed's own 1X line shows in a recording (:func:`running_speed_line`)
LINE_CLASSES = ("separate", "merged", "below noise")


def running_speed_line(waveforms_um: np.ndarray, fs_hz: float, speed_rpm: float) -> str:
    """How the true running speed's 1X line shows in the summed Hann spectrum the estimator searches.

    ``"separate"``: a local maximum within half a bin of the true 1X, at least ``SPEED_LINE_MIN_SNR``
    times the median spectrum (what any spectral estimator needs to find it); ``"merged"``: the 1X bins
    stand above the noise, but inside the main lobe of a neighbouring line (oil whip locked near half the
    speed puts its 2nd harmonic there) — not resolvable at this record length; ``"below noise"``: the
    1X bins are under ``SPEED_LINE_MIN_SNR`` times the median (the speed is not in the signal's 1X).
    """
    x = waveforms_um - waveforms_um.mean(axis=1, keepdims=True)
    n = x.shape[1]
    n_fft = fast_length(n)
    power = np.sum(np.abs(np.fft.rfft(x * hann(n), n=n_fft, axis=-1)) ** 2, axis=0)
    df = fs_hz / n_fft
    floor = float(np.median(power[3:int(0.45 * fs_hz / df)]))
    k_true = speed_rpm / 60.0 / df
    k0 = int(round(k_true))
    level = cfg.SPEED_LINE_MIN_SNR * floor
    peaks = [k for k in (k0 - 1, k0, k0 + 1) if power[k] >= power[k - 1] and power[k] > power[k + 1]
             and abs(k - k_true) <= 0.5 + 1e-9]
    if peaks and power[peaks[0]] >= level:
        return "separate"
    return "merged" if power[k0 - 1:k0 + 2].max() >= level else "below noise"
