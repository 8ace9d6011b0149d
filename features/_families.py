"""Line families of a record and the readings that tell a running speed from what is not one: a sub-synchronous
whirl or whip (its family, its combination lines with the running speed, a 1X hidden beside its 2nd harmonic), a
half-speed whirl, period-n motion. Used by the running-speed estimate (:mod:`._speed`)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rotordiag.core.notes import Note

from . import _config as cfg
from ._lines import (
    _circular_fraction,
    _circular_fraction_at,
    _hann_kernel,
    _line_amplitude,
    _lines_at,
    _local_peak_ratio,
    refine_line_hz,
)

__all__: list[str] = []


class _Family(NamedTuple):
    """A candidate running speed and its 1X, 2X, 3X lines (built by ``_speed._candidate_families``)."""

    f_hz: float
    n_present: int              # lines above the noise and at least SPEED_HARMONIC_MIN_REL of the largest line
    amp_present: float          # their summed amplitude (√power)
    n_above_noise: int          # lines above the noise (SPEED_LINE_MIN_SNR × the median spectrum)
    amp_above_noise: float      # their summed amplitude


def _above_subsynchronous(x: np.ndarray, spec: np.ndarray, fs: float, df: float,
                          candidates: list[_Family]) -> tuple[float, str | None]:
    """The running speed when the best-ranked line family is a sub-synchronous whirl or whip.

    Oil whirl and whip are self-excited: their line (0.4–0.5X, or locked near the first natural
    frequency, down to about 0.3X) and its harmonics form a family of their own, often far
    stronger than the running speed's (simulated whip: 1X at 0.2 % of the whip amplitude). A
    family above the best-ranked one, with at least two of its 1X–3X lines above the noise,
    whose frequency is more than ``1 / SPEED_SUBSYNC_MAX_RATIO`` times the best one's and not
    an integer multiple of it (within ``SPEED_INTEGER_RATIO_TOL`` after refining both lines), is
    an independent source above a sub-synchronous one: no self-excited whirl runs above the
    running speed, so one such family is the running speed: the one with the most evidence, its
    lines above the noise times their summed amplitude. The whirl's combination lines with the
    running speed (2Ω − ω, Ω ± ω: mixing products, weaker than the 1X that makes them) build
    families too, and on a long record with a low noise floor one of them can show three lines
    above the noise where the running speed shows two (1X and 2X) at ten times the amplitude,
    so the evidence is weighed by amplitude, not by counting lines (docs/features.md). Families at an exact
    integer ratio (a 2X-dominated signal, or period-n motion) are left to the ranking, and so are
    families whose own line beats in a nearly flat orbit (backward / forward above
    ``SPEED_RUNNING_MAX_BACKWARD``: a combination line of the whirl with the running speed).
    """
    f_best = candidates[0].f_hz
    higher = [c for c in candidates[1:] if f_best < cfg.SPEED_SUBSYNC_MAX_RATIO * c.f_hz and c.n_above_noise >= 2]
    if not higher:
        return f_best, None
    fb = refine_line_hz(x, fs, f_best, iterations=2)
    if abs(fb - f_best) > 2 * df:
        fb = f_best
    independent = []
    for c in higher:
        fc = refine_line_hz(x, fs, c.f_hz, iterations=2)
        if abs(fc - c.f_hz) > 2 * df:
            fc = c.f_hz
        r = fc / fb
        if (abs(r - round(r)) > cfg.SPEED_INTEGER_RATIO_TOL * r
                and not _circular_fraction_at(spec, c.f_hz, df) > cfg.SPEED_RUNNING_MAX_BACKWARD):
            independent.append(c)
    if not independent:
        return f_best, None
    best = max(independent, key=lambda c: c.n_above_noise * c.amp_above_noise)
    note = Note("speed_above_subsynchronous", line_cpm=60 * f_best, ratio_x=f_best / best.f_hz,
                speed_rpm=60 * best.f_hz)
    return best.f_hz, note


def _doubles(candidates: list[_Family], f: float, n_lines: int, df: float) -> list[_Family]:
    """The candidate families at twice ``f`` (within 1.5 bins) with at least ``n_lines`` lines present: each
    explains the record as well as the family at ``f`` (period-2 motion and a 2X-dominated machine look alike)."""
    return [c for c in candidates if abs(c.f_hz - 2 * f) < 1.5 * df and c.n_present >= n_lines]


def _half_speed_whirl(spec: np.ndarray, df: float,
                      candidates: list[_Family]) -> str | None:
    """Never a sub-harmonic: move the family at twice the best one's frequency to the front when the
    best one is a half-speed whirl or the 1/2X of period-2 motion.

    A family at 2f with as many lines present as the best family at f explains the record as well,
    spectrally. Physics decides: a self-excited whirl and the sub-harmonic of period-2 motion whirl in
    nearly circular orbits (backward / forward below ``SPEED_HALF_WHIRL_MAX_BACKWARD``); the
    running speed's own 1X is elliptical in fluid-film bearings, and then 2f is its 2X (a
    flexible coupling's may be the larger line) and f is kept. The choice is reported as
    ambiguous. Returns the warning, or None when ``candidates`` is left as it is.
    """
    f0, n0 = candidates[0].f_hz, candidates[0].n_present
    double = _doubles(candidates, f0, n0, df)
    if not double:
        return None
    circ = _circular_fraction_at(spec, f0, df)
    if not circ < cfg.SPEED_HALF_WHIRL_MAX_BACKWARD:
        return None
    candidates.remove(double[0])
    candidates.insert(0, double[0])
    return Note("speed_estimate_ambiguous", detail=f"{60 * double[0].f_hz:.1f} r/min chosen; the line at {60 * f0:.1f} cpm, with "
            f"harmonics of its own, whirls in nearly circular orbits (backward / forward {circ:.3f}) and is read as "
            f"a half-speed whirl or sub-harmonic; if the machine runs at {60 * f0:.1f} r/min give speed_rpm or "
            "keyphasor_times_s")


def _period_n(power: np.ndarray, logp: np.ndarray, df: float, f: float, level: float, f_hi: float,
              sidebands: np.ndarray) -> tuple[int, int]:
    """Whether the harmonic comb of ``f`` reads as period-n motion of a machine running at n·f: (n, strength).

    A machine running at ``f`` has a comb of 1X, 2X, 3X … lines that rarely peaks at 3X; in
    period-n motion at the running speed nf (a 1/nX sub-harmonic with its 2/nX, 3/nX … from the
    nonlinear bearings) every line is a harmonic of f as well, but the running speed's own 1X and
    2X, at nf and 2nf, stand above their neighbours in the comb, below the sub-harmonic at f.
    With the genuine lines of :func:`_line_amplitude` at ``level``: strength 0 when the line at nf is
    not larger than those at (n − 1)f and (n + 1)f, or holds less than ``SPEED_PERIOD3_MIN_REL`` or
    more than ``SPEED_PERIOD3_MAX_REL`` of the line at f (a machine whose nX is that large is running
    at f, near a resonance at nX), or when nf lies above ``f_hi``; 2 when the line at 2nf also stands
    above those at (2n − 1)f and (2n + 1)f; else 1.

    n = 3 is tried first and returned at either strength. Then n = 4 … ``SPEED_PERIOD_MAX_N``, only at
    strength 2 and with every line f … nf present (period-n motion fills the comb with its
    sub-harmonics k/nX): a flexible coupling's comb peaks at 4X and 8X as well, so these are reported
    for a warning, never to change the speed (the caller's choice). Else (0, 0). The strengths' bounds and
    the recordings they were set on: docs/features.md, "Measurements behind the speed estimate's thresholds".
    """
    a = [0.0] * (2 * cfg.SPEED_PERIOD_MAX_N + 2)
    known = 0
    for n in range(3, cfg.SPEED_PERIOD_MAX_N + 1):
        if n * f > f_hi or (2 * n + 1) * f >= df * (power.size - 3):
            break
        for m in range(known + 1, 2 * n + 2):
            a[m] = _line_amplitude(power, logp, m * f, df, level, sidebands)
        known = 2 * n + 1
        if not (a[1] > 0 and cfg.SPEED_PERIOD3_MIN_REL * a[1] <= a[n] <= cfg.SPEED_PERIOD3_MAX_REL * a[1]
                and a[n] > max(a[n - 1], a[n + 1])):
            continue
        doubled = a[2 * n] > max(a[2 * n - 1], a[2 * n + 1])
        if n == 3:
            return 3, 2 if doubled else 1
        if doubled and all(v > 0 for v in a[1:n + 1]):
            return n, 2
    return 0, 0


def _hidden_running_line(spec: np.ndarray, fs: float, n: int, df: float,
                         f_whirl: float) -> tuple[float, float, float] | None:
    """The running speed's 1X hidden in the main lobe of an oil whirl's 2nd harmonic, by a two-line fit.

    Oil whirl runs just below half the running speed Ω (0.42–0.49X), so its 2nd harmonic 2ω lies
    within a bin or two below Ω on a record of a few dozen revolutions: the two lines merge into
    one spectral peak and no peak-picking sees the 1X. Here the Hann spectra of the channels
    (``spec``: rfft of the ``n``-sample records, mean removed, times the Hann window, bin width
    ``df``) between 2ω − 5 and 2ω + 8 record bins (fs / n) are fitted, channel by channel,
    with a line at exactly 2ω (``f_whirl`` is the refined whirl) and a second line at g, for g
    from 2ω + ``SPEED_HIDDEN_MIN_BINS`` to 2ω + ``SPEED_HIDDEN_MAX_BINS`` record bins (Ω > 2ω), the
    line shapes from the window's exact transform. Returns (g in Hz, residual with g over the
    residual with 2ω alone, amplitude of g over that of 2ω) for the best g when the second line
    lowers the residual below ``SPEED_HIDDEN_MAX_RESIDUAL`` of the one-line fit, else None.
    """
    from scipy.optimize import minimize_scalar

    dfr = fs / n
    h2 = 2.0 * f_whirl
    k_lo, k_hi = max(int(np.ceil((h2 - 5.0 * dfr) / df)), 1), min(int(np.floor((h2 + 8.0 * dfr) / df)), spec.shape[1] - 1)
    if k_hi - k_lo < 8:
        return None
    nu = np.arange(k_lo, k_hi + 1) * df
    y = spec[:, k_lo:k_hi + 1].T                            # (bins, channels)
    k0 = _hann_kernel(2 * np.pi * (nu - h2) / fs, n)

    def fit(g: float | None) -> tuple[float, np.ndarray]:
        a = k0[:, None] if g is None else np.stack([k0, _hann_kernel(2 * np.pi * (nu - g) / fs, n)], axis=1)
        z, *_ = np.linalg.lstsq(a, y, rcond=None)
        return float(np.sum(np.abs(y - a @ z) ** 2)), z

    r1, _ = fit(None)
    if not r1 > 0:
        return None
    grid = h2 + np.arange(cfg.SPEED_HIDDEN_MIN_BINS, cfg.SPEED_HIDDEN_MAX_BINS + 1e-9, 0.05) * dfr
    r = np.array([fit(float(g))[0] for g in grid])
    i = int(np.argmin(r))
    best = minimize_scalar(lambda v: fit(v)[0], bounds=(grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]),
                           method="bounded", options={"xatol": 1e-3 * dfr})  # between the grid neighbours
    g = float(best.x)
    r2, z = fit(g)
    if not r2 < cfg.SPEED_HIDDEN_MAX_RESIDUAL * r1:
        return None
    a0, ag = np.sqrt(np.sum(np.abs(z[0]) ** 2)), np.sqrt(np.sum(np.abs(z[1]) ** 2))
    return g, r2 / r1, float(ag / a0) if a0 > 0 else float("inf")


#: the lattice lines mΩ + kω a whirl / whip ω makes with the running speed Ω: 1X and Ω ± ω (bearing
#: nonlinearity), the mirror images 2Ω − kω of the whirl's harmonics (2X asymmetry) ending at 2X, 3X
_COMBINATIONS: tuple[tuple[int, tuple[int, ...]], ...] = ((1, (0, -1, 1)), (2, (0, -1, -2, -3, -4)), (3, (0,)))


def _combination_partners(power: np.ndarray, logp: np.ndarray, df: float, floor: float, f_w: float,
                          foreign_hz: list[float], f_lo: float, f_hi: float,
                          f_top: float, sidebands: np.ndarray) -> list[tuple[float, float, int, float]]:
    """Candidate running speeds Ω when the dominant line family at ``f_w`` is a sub-synchronous whirl / whip.

    A whirl or whip line ω is not locked to the running speed Ω, but it mixes with it: the
    rotor's 2X asymmetry (misalignment, gravity, a two-pole rotor) turns the forward whirl ω and
    its harmonics kω into lines at 2Ω − kω (their mirror image about Ω), and the nonlinear
    bearings add Ω ± kω. Every line of the record then lies on the lattice mΩ + kω, and the
    running speed's own 1X line is there even when it is a thousand times weaker than the whip.

    Candidates are built from the lines ``foreign_hz`` that are not harmonics of ω (each read as
    1X, Ω ± kω or 2Ω − kω) and kept when ω ≤ ``SPEED_SUBSYNC_MAX_RATIO`` Ω (a self-excited whirl
    runs below the running speed) and their own 1X or 2X line is a local maximum. The lines of the
    record (local maxima at least ``SPEED_PARTNER_LINE_SNR`` × the median spectrum, up to
    ``f_top``) are then read as lattice points ``_COMBINATIONS`` (1X, Ω ± ω, 2Ω − kω for
    k = 0…4, 3X): a
    candidate scores the log-power of each line it explains (within ``SPEED_PARTNER_TOL_BINS``
    of the lattice point) minus that of each line it leaves unexplained, so that a lattice with
    another basis (Ω' = 2Ω − ω reads part of the 2Ω − kω comb as Ω' ± ω, but not its top, the
    2X at 2Ω) loses to the one that explains every line. A candidate needs at least
    ``SPEED_PARTNER_MIN_COMBINATIONS`` combination lines.

    Returns
    -------
    list of (Ω in Hz, score, combination lines explained, 1X power over the floor), best first;
    empty when no candidate qualifies.
    """
    tol = cfg.SPEED_PARTNER_TOL_BINS
    k_top = min(int(f_top / df), power.size - 2)
    kk = np.arange(2, k_top)
    k_lines = kk[_lines_at(power, kk, cfg.SPEED_PARTNER_LINE_SNR * floor, sidebands)]
    den = logp[k_lines - 1] - 2 * logp[k_lines] + logp[k_lines + 1]
    delta = np.where(den < 0, 0.5 * (logp[k_lines - 1] - logp[k_lines + 1]) / np.where(den < 0, den, -1.0), 0.0)
    f_lines = (k_lines + delta) * df
    w_lines = np.log(power[k_lines] / floor)
    j = np.rint(f_lines / f_w)
    whirl_family = (j >= 1) & (np.abs(f_lines - j * f_w) <= 1.5 * df)

    def near_whirl_harmonic(f: float) -> bool:
        i = round(f / f_w)
        return i >= 1 and abs(f - i * f_w) < 2.5 * df

    seeds: list[float] = []
    for g in foreign_hz:
        seeds += [g] + [(g + i * f_w) / 2 for i in range(0, 5)] + [g + i * f_w for i in (-2, -1, 1, 2)] + [g / 3]
    tried: list[float] = []
    scored: list[tuple[float, float, int, float]] = []
    for om in seeds:
        if not (f_lo <= om <= f_hi) or f_w > cfg.SPEED_SUBSYNC_MAX_RATIO * om or near_whirl_harmonic(om):
            continue
        if any(abs(om - t) < 0.5 * df for t in tried):
            continue
        tried.append(om)
        own = np.abs(f_lines - om) <= tol * df
        own2 = np.abs(f_lines - 2 * om) <= 2 * tol * df
        if not (own.any() or own2.any()):
            continue                                    # a running speed shows its 1X or its 2X line
        om_c = float(f_lines[own][np.argmax(w_lines[own])]) if own.any() else \
            float(f_lines[own2][np.argmax(w_lines[own2])]) / 2
        explained = whirl_family.copy()
        n_comb = 0
        for m, ks in _COMBINATIONS:
            for k in ks:
                hit = np.abs(f_lines - (m * om_c + k * f_w)) <= tol * df * (2 if k == 0 and m > 1 else 1)
                n_comb += int(k != 0 and bool((hit & ~explained).any()))
                explained |= hit
        if n_comb < cfg.SPEED_PARTNER_MIN_COMBINATIONS or any(abs(om_c - c[0]) < 0.5 * df for c in scored):
            continue
        score = float(w_lines[explained & ~whirl_family].sum() - w_lines[~explained].sum())
        scored.append((om_c, score, n_comb, float(np.exp(w_lines[own].max())) if own.any() else 0.0))
    scored.sort(key=lambda s: -s[1])
    return scored


def _weak_lines_above(power: np.ndarray, df: float, floor: float, f1: float, f_hi: float,
                      sidebands: np.ndarray) -> list[float]:
    """Lines (local maxima ``SPEED_PARTNER_LINE_SNR`` × the median spectrum) above f1 / ``SPEED_SUBSYNC_MAX_RATIO``
    and up to ``f_hi`` that are not within 1.5 bins of a harmonic of ``f1``: if ``f1`` were a whirl / whip,
    one of them could be the running speed's weak 1X line."""
    k_lo = int(np.ceil(f1 / cfg.SPEED_SUBSYNC_MAX_RATIO / df))
    k_hi = min(int(f_hi / df), power.size - 2)
    kk = np.arange(max(k_lo, 2), k_hi + 1)
    if kk.size == 0:
        return []
    level = max(cfg.SPEED_PARTNER_LINE_SNR * floor, cfg.SPEED_WEAK_LINE_MIN_REL ** 2 * float(power.max()))
    f = kk[_lines_at(power, kk, level, sidebands)] * df
    m = np.rint(f / f1)
    return [float(v) for v in f[np.abs(f - m * f1) > 1.5 * df]]


def _on_lattice(f: float, om: float, w: float, df: float) -> bool:
    """Whether ``f`` lies within 1.5 bins of a line mΩ + kω (m = 0…3, |k| ≤ 6) of speed ``om`` and whirl ``w``."""
    return any(abs(f - m * om - k * w) <= 1.5 * df for m in range(4) for k in range(-6, 7) if (m, k) != (0, 0))


def _refine_partner(x: np.ndarray, fs: float, df: float, power: np.ndarray, floor: float, om: float, w: float,
                    sidebands: np.ndarray) -> float:
    """Refine a running speed ``om`` found from whirl combination lines (see :func:`_combination_partners`).

    Each lattice line mΩ + kω (m = 1…3, |k| ≤ 4) at least ``SPEED_LINE_MIN_SNR`` above the noise and
    clear of the whirl's harmonics is refined by :func:`refine_line_hz`; Ω = (f − kω) / m from each,
    averaged with weights m² × power (the frequency error of a line falls as its amplitude grows, and
    divides by m). Falls back to ``om`` when no line qualifies or the result wanders off by more than a bin.
    """
    num = den = 0.0
    for m in (1, 2, 3):
        for k in range(-4, 5):
            q = m * om + k * w
            if q <= 2 * df or q > 0.45 * fs or (k != 0 and abs(q - round(q / w) * w) < 2.5 * df):
                continue
            r = _local_peak_ratio(power, q, df, floor, cfg.SPEED_PARTNER_TOL_BINS, sidebands)
            if r < cfg.SPEED_LINE_MIN_SNR:
                continue
            fq = refine_line_hz(x, fs, q, iterations=2)
            if abs(fq - q) > df:
                continue
            wgt = m * m * r
            num += wgt * (fq - k * w) / m
            den += wgt
    if den == 0.0:
        return om
    f = num / den
    return f if abs(f - om) <= df else om


def _hidden_1x(x: np.ndarray, spec: np.ndarray, fs: float, df: float, k_top: int, f: float,
               c_lo: float, c_hi: float) -> tuple[float, str] | None:
    """The running speed when the chosen ``f`` is an oil whirl (or its 2nd harmonic) whose 2nd harmonic hides the 1X.

    Applies when the largest line (FFT bin ``k_top``) whirls in nearly circular orbits (backward /
    forward below ``SPEED_HALF_WHIRL_MAX_BACKWARD``) and ``f`` is that line or twice it: the running
    speed is then sought by :func:`_hidden_running_line`. Returns (speed in Hz, the warning) when a
    line within ``[c_lo, c_hi]`` is found, else None. The estimate stays "ambiguous": it rests on a fit.
    """
    f_top = k_top * df
    if not (abs(f - f_top) <= 1.5 * df or abs(f - 2 * f_top) <= 2.5 * df):
        return None
    circ = _circular_fraction(spec, k_top)
    if not circ < cfg.SPEED_HALF_WHIRL_MAX_BACKWARD:        # NaN (no x/y pair): no
        return None
    f_w = refine_line_hz(x, fs, f_top, iterations=2)
    if abs(f_w - f_top) > 2 * df:
        f_w = f_top
    found = _hidden_running_line(spec, fs, x.shape[1], df, f_w)
    if found is None or not (c_lo <= found[0] <= c_hi):
        return None
    g, rel_res, rel_amp = found
    return g, Note("speed_estimate_ambiguous", detail=f"{60 * g:.1f} r/min chosen: the largest line, at {60 * f_w:.1f} cpm "
               f"({f_w / g:.3f}X), whirls in nearly circular orbits (backward / forward {circ:.3f}), read as oil "
               f"whirl; the running speed's 1X ({rel_amp:.2f} × the whirl's 2nd harmonic) lies "
               f"{(g - 2 * f_w) * x.shape[1] / fs:.1f} record bins above that harmonic, inside its main lobe, and is "
               f"separated by a two-line fit (residual {rel_res:.3f} of one line's); confirm with speed_rpm or "
               "keyphasor_times_s")
