"""Running speed and shaft angle: keyphasor, given speed, or estimated from the signal."""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from rotordiag.core.notes import Note

from . import _config as cfg
from ._families import (
    _above_subsynchronous,
    _combination_partners,
    _doubles,
    _Family,
    _half_speed_whirl,
    _hidden_1x,
    _on_lattice,
    _period_n,
    _refine_partner,
    _weak_lines_above,
)
from ._keyphasor import keyphasor_fault, pulses_in_record
from ._lines import (
    _circular_fraction,
    _circular_fraction_at,
    _hann_amplitude_at,
    _line_amplitude,
    _lines_at,
    _modulation_sidebands,
    _non_harmonic_lines,
    refine_line_hz,
)
from ._spectrum import fast_length, hann_spectra
from ._speed_lock import locked_speed_hz

__all__ = ["ShaftAngle", "shaft_angle", "estimate_speed_hz", "KEYPHASOR_INTERVALS"]

#: ``speed_source`` of a faulty keyphasor's speed: the median of its sound pulse intervals (locked to the signal's
#: lines), with the orders tracked at that steady speed and phases from the first sample — not a speed the user gave
KEYPHASOR_INTERVALS = "keyphasor intervals"


@dataclass
class ShaftAngle:
    """The shaft angle over the analysed segment (a whole number of revolutions).

    ``theta_rad[i]`` is the angle at sample ``start + i``; θ = 0 at the keyphasor pulse that
    opens the segment, or at the first sample when there is no keyphasor.
    """

    speed_rpm: float
    source: str                 # "keyphasor" | "given" | "estimated" | KEYPHASOR_INTERVALS
    start: int
    stop: int
    theta_rad: np.ndarray
    n_revs: int
    rev_times_s: np.ndarray     # (n_revs,) time at which each analysed revolution starts (θ = 2πm)
    min_samples_per_rev: float
    warnings: list[str] = field(default_factory=list)


def _too_slow_sampling(spr: float, fs: float, f1: float) -> ValueError:
    return ValueError(
        f"sample_rate_hz {fs:g} gives only {spr:.2f} samples per revolution at {60 * f1:.1f} r/min; "
        f"3X must lie below 0.75 × Nyquist, so record at >= {cfg.MIN_SAMPLES_PER_REV:g} samples per "
        f"revolution (sample_rate_hz >= {cfg.MIN_SAMPLES_PER_REV * f1:.1f} Hz)")


def _too_short(n_revs: float, rpm: float, fs: float, n: int, source: str) -> ValueError:
    need_s = cfg.MIN_REVS * 60.0 / rpm
    # a speed typed in Hz (rev/s) reads 60 times too slow: say so when 60 times it is a plausible running speed
    # that the record covers
    hz = (f"; if {rpm:g} is the speed in Hz (revolutions per second), give speed_rpm = {60 * rpm:g}"
          if source == "speed given" and n_revs * 60 >= cfg.MIN_REVS
          and cfg.SPEED_SEARCH_RPM[0] <= 60 * rpm <= cfg.SPEED_SEARCH_RPM[1] else "")
    return ValueError(
        f"the record covers {n_revs:.2f} revolutions at {rpm:.1f} r/min ({source}); at least "
        f"{cfg.MIN_REVS} whole revolutions are needed for reliable 1X–3X estimates — record at least "
        f"{need_s:.3f} s ({int(np.ceil(need_s * fs))} samples at {fs:g} Hz; this one has {n}){hz}")


@dataclass(frozen=True)
class _Spectrum:
    """The record's spectra and levels that every stage of the speed estimate reads (:func:`_spectrum`)."""

    x: np.ndarray               # (channels, n): the record, each channel's mean removed
    spec: np.ndarray            # (channels, bins): Hann spectra of ``x``
    power: np.ndarray           # (bins,): their summed power
    logp: np.ndarray            # log of ``power`` (peak interpolation)
    fs: float                   # sample rate, Hz
    df: float                   # bin width, Hz
    f_lo: float                 # the search range, Hz (SPEED_SEARCH_RPM, and 3X below the Nyquist limit)
    f_hi: float
    c_lo: float                 # where the running speed may lie, Hz: the search range within a stated range
    c_hi: float
    floor: float                # median power of the search range
    sidebands: np.ndarray       # (bins,) bool: modulation sidebands, no line for any line test
    peak_idx: np.ndarray        # bins of the largest peaks in the search range, strongest first

    @property
    def snr_level(self) -> float:
        """Power at which a line stands out of the noise."""
        return cfg.SPEED_LINE_MIN_SNR * self.floor

    @property
    def p_max(self) -> float:
        """Power of the largest peak in the search range."""
        return float(self.power[self.peak_idx[0]])

    @property
    def k_top(self) -> int:
        """Bin of the largest peak in the search range."""
        return int(self.peak_idx[0])

    @property
    def f_top(self) -> float:
        """Frequency of the largest peak in the search range, Hz (its bin)."""
        return self.k_top * self.df


def estimate_speed_hz(data: np.ndarray, fs: float,
                      speed_range_hz: tuple[float, float] | None = None) -> tuple[float, list[str]]:
    """Running speed (Hz) from the waveforms: the refined spectral line of 1X.

    With ``speed_range_hz`` the estimate without it is kept when it lies in the range (with its
    warnings); only when it does not (or fails) is the range-restricted search of
    :func:`_estimate_speed_hz` used. So a stated range can turn an answer outside it into one
    inside it, or into a refusal, but never change an answer that already agreed with it.
    Parameters, returns and notes as :func:`_estimate_speed_hz`.
    """
    if speed_range_hz is None:
        return _estimate_speed_hz(data, fs, None)
    try:
        f, warnings = _estimate_speed_hz(data, fs, None)
        if float(speed_range_hz[0]) <= f <= float(speed_range_hz[1]):
            return f, warnings
    except ValueError:
        pass
    return _estimate_speed_hz(data, fs, speed_range_hz)


@dataclass
class _Choice:
    """The running speed as the whirl stage (:func:`_whirl_stage`) leaves it."""

    family: _Family             # the family read as the running speed (with ``f_partner``: the whirl's)
    f_hz: float                 # the speed so far, Hz
    f_first: float              # the best-ranked family's frequency before the stage (the whirl when switched)
    switched: str | None = None  # the note when a family above a sub-synchronous one was taken
    whip_hz: float | None = None  # the refined whirl / whip when the speed came from its combination lines
    f_partner: float | None = None  # that speed, refined
    warnings: list[str] = field(default_factory=list)


def _spectrum(data: np.ndarray, fs: float, speed_range_hz: tuple[float, float] | None) -> _Spectrum:
    """The spectra, the search range, the noise floor and the largest peaks of a record (the estimate's first
    stage). Raises ``ValueError`` when the record cannot resolve the search range, the stated range lies outside
    it, or no line stands out of the noise."""
    n = data.shape[1]
    n_fft = fast_length(n)
    x, spec, power = hann_spectra(data)
    df = fs / n_fft
    f_lo = max(cfg.SPEED_SEARCH_RPM[0] / 60.0, 3 * df)
    f_hi = min(cfg.SPEED_SEARCH_RPM[1] / 60.0, fs / cfg.MIN_SAMPLES_PER_REV)
    k_lo, k_hi = int(np.ceil(f_lo / df)), min(int(np.floor(f_hi / df)), power.size - 2)
    if k_hi <= k_lo + 2:
        raise ValueError(
            f"cannot estimate the running speed: the record ({n} samples at {fs:g} Hz) is too short to resolve "
            f"{cfg.SPEED_SEARCH_RPM[0]:g}–{cfg.SPEED_SEARCH_RPM[1]:g} r/min; give speed_rpm or keyphasor_times_s")
    c_lo, c_hi = f_lo, f_hi
    if speed_range_hz is not None:
        c_lo, c_hi = max(f_lo, float(speed_range_hz[0])), min(f_hi, float(speed_range_hz[1]))
        if c_lo > c_hi:
            raise ValueError(
                f"speed_range_rpm {60 * speed_range_hz[0]:g}–{60 * speed_range_hz[1]:g} r/min lies outside what this "
                f"record can resolve ({60 * f_lo:.0f}–{60 * f_hi:.0f} r/min at {fs:g} Hz); check the range or give speed_rpm")
    band = power[k_lo:k_hi + 1]
    floor = float(np.median(band))
    sidebands = _modulation_sidebands(power, df, cfg.SPEED_PARTNER_LINE_SNR * floor)
    inner = band[1:-1]
    is_peak = (inner >= band[:-2]) & (inner > band[2:]) & ~sidebands[k_lo + 1:k_hi]
    peak_idx = np.nonzero(is_peak)[0] + k_lo + 1
    if peak_idx.size == 0 or power[peak_idx].max() < cfg.SPEED_LINE_MIN_SNR * floor:
        raise ValueError(
            "cannot estimate the running speed: no spectral line stands out of the noise between "
            f"{cfg.SPEED_SEARCH_RPM[0]:g} and {cfg.SPEED_SEARCH_RPM[1]:g} r/min; give speed_rpm or keyphasor_times_s")
    peak_idx = peak_idx[power[peak_idx] >= cfg.SPEED_LINE_MIN_SNR * floor]
    peak_idx = peak_idx[np.argsort(-power[peak_idx], kind="stable")[:cfg.SPEED_CANDIDATE_PEAKS]]
    logp = np.log(np.maximum(power, np.finfo(float).tiny))
    return _Spectrum(x, spec, power, logp, fs, df, f_lo, f_hi, c_lo, c_hi, floor, sidebands, peak_idx)


def _seed_bins(s: _Spectrum, ranged: bool) -> np.ndarray:
    """The peaks whose frequency (or a half or a third of it) may be the running speed: the largest peaks, and
    with a stated range every line whose 1st, 2nd or 3rd sub-multiple lies in it (a weak 1X, or its 2X, 3X,
    inside the range need not be among the largest peaks)."""
    if not ranged:
        return s.peak_idx
    extra: list[int] = []
    for m in (1, 2, 3):
        a, b = max(int(np.floor(m * s.c_lo / s.df)), 1), min(int(np.ceil(m * s.c_hi / s.df)), s.power.size - 2)
        kk = np.arange(a, b + 1)
        if kk.size:
            ok = _lines_at(s.power, kk, s.snr_level, s.sidebands)
            extra.extend(int(k) for k in kk[ok] if k not in s.peak_idx)
    return np.concatenate([s.peak_idx, np.asarray(sorted(set(extra), key=lambda k: -s.power[k]), dtype=np.int64)])


def _candidate_families(s: _Spectrum, seed_idx: np.ndarray) -> list[_Family]:
    """Each seed peak ``f_p`` (interpolated) and its sub-multiples ``f_p/2``, ``f_p/3`` in the search range, as a
    :class:`_Family` when it has a 1X line of its own (a running speed always shows one), at most one family
    within 1.5 bins. A line counts as present when it stands out of the noise and its amplitude is at least
    ``SPEED_HARMONIC_MIN_REL`` of the largest line; the m-th harmonic of an interpolated peak is m times as far
    off (a wandering speed broadens the peak): its window is m × ``SPEED_HARMONIC_TOL_BINS`` bins, at most
    ``SPEED_HARMONIC_MAX_TOL_BINS``. Raises ``ValueError`` when there is none."""
    present_level = max(s.snr_level, cfg.SPEED_HARMONIC_MIN_REL ** 2 * s.p_max)
    logp, df = s.logp, s.df
    families: list[_Family] = []
    for k in seed_idx:
        den = logp[k - 1] - 2 * logp[k] + logp[k + 1]
        delta = 0.5 * (logp[k - 1] - logp[k + 1]) / den if den < 0 else 0.0
        fp = (k + delta) * df
        for d in (1, 2, 3):
            f = fp / d
            if not (s.f_lo <= f <= s.f_hi) or any(abs(f - c.f_hz) < 1.5 * df for c in families):
                continue
            weak = [_line_amplitude(s.power, logp, m * f, df, s.snr_level, s.sidebands,
                                    min(cfg.SPEED_HARMONIC_TOL_BINS * m, cfg.SPEED_HARMONIC_MAX_TOL_BINS))
                    for m in (1, 2, 3)]
            if weak[0] <= 0.0:
                continue
            amps = [a if a * a >= present_level else 0.0 for a in weak]
            families.append(_Family(f, int(sum(a > 0 for a in amps)), float(sum(amps)),
                                    int(sum(a > 0 for a in weak)), float(sum(weak))))
    if not families:
        raise ValueError("cannot estimate the running speed: no candidate line in the search range; "
                         "give speed_rpm or keyphasor_times_s")
    return families


def _ranked(s: _Spectrum, families: list[_Family], ranged: bool) -> tuple[list[_Family], bool]:
    """The families ranked by lines present, then by their summed amplitude, and whether the running speed can
    only come from a whirl's combination lines (``only_partner``: a stated range with no family in it; the best
    family outside, a whirl / whip, is then kept to find them).

    With a stated range only its families are ranked, and when the largest line lies below the range (a whirl /
    whip) its harmonics are no running speeds. Never a sub-harmonic: a family at twice the best one's frequency
    with as many lines present, whose own line is far the stronger (``SPEED_HALF_MAX_REL``), is moved to the front
    (a faint line at half its frequency, with the lines between, is a sub-harmonic, not a running speed with a 2X
    thirty times its 1X).
    """
    in_range = [c for c in families if s.c_lo <= c.f_hz <= s.c_hi]
    if ranged and s.f_top < s.c_lo:
        in_range = [c for c in in_range if abs(c.f_hz - round(c.f_hz / s.f_top) * s.f_top) > 1.5 * s.df]
    only_partner = ranged and not in_range
    if ranged and in_range:
        families = in_range
    families.sort(key=lambda c: (-c.n_present, -c.amp_present))
    f0 = families[0].f_hz
    double = [c for c in _doubles(families, f0, families[0].n_present, s.df)
              if _hann_amplitude_at(s.power, f0, s.df) < cfg.SPEED_HALF_MAX_REL * _hann_amplitude_at(s.power, c.f_hz, s.df)]
    if double:
        families.remove(double[0])
        families.insert(0, double[0])
    return families, only_partner


def _no_line_in_range(s: _Spectrum) -> ValueError:
    merged = ""
    if s.f_top < s.c_lo and s.c_lo <= 2.0 * s.f_top <= s.c_hi:
        revs = s.x.shape[1] / s.fs * s.c_lo
        merged = (f"; the range holds the 2nd harmonic of the largest line, a whirl at {60 * s.f_top:.0f} cpm, and no "
                  f"running speed's 1X could be told apart from it on these {revs:.0f} revolutions — record longer (a "
                  "record of N revolutions tells apart lines about 2/N of the running speed apart) or")
    return ValueError(
        f"cannot estimate the running speed: no spectral line of a running speed (1X with its own line) lies "
        f"within speed_range_rpm {60 * s.c_lo:.0f}–{60 * s.c_hi:.0f} r/min{merged or '; check the range or'} give "
        "speed_rpm or keyphasor_times_s")


def _whirl_stage(s: _Spectrum, families: list[_Family], only_partner: bool) -> _Choice:
    """The running speed when the best-ranked family may be a sub-synchronous whirl / whip.

    In this order: a family above it that is no harmonic of it (:func:`_above_subsynchronous`); else, when the
    best family's line is the largest and whirls in a nearly circular orbit (or a stated range holds no family),
    the running speed whose combination lines with it explain the record (:func:`_combination_partners`; flagged
    ambiguous when its own 1X is weak, a rival scores nearly as well, a runner-up one whirl frequency away has
    the stronger 1X, or its lattice scores ≤ 0); else a half-speed whirl read at twice its frequency (:func:`_half_speed_whirl`). Reorders
    ``families`` in the last case. Raises ``ValueError`` when only a partner could give the speed and none does.
    """
    first = families[0]
    if not only_partner:
        f_sw, switched = _above_subsynchronous(s.x, s.spec, s.fs, s.df, families)
        if switched is not None:
            family = next(c for c in families if c.f_hz == f_sw)
            return _Choice(family, f_sw, first.f_hz, switched=switched, warnings=[switched])
    f_best, df = first.f_hz, s.df
    # the whirl / whip a partner is sought for is the largest line and whirls in a nearly circular
    # orbit; the running speed's elliptical 1X read as one finds spurious partners among its own
    # combination lines (with a speed range and no running speed in it, the search is the only way)
    whirl_like = (abs(s.f_top - f_best) <= 1.5 * df
                  and not _circular_fraction_at(s.spec, f_best, df) >= cfg.SPEED_PARTNER_MAX_BACKWARD)  # NaN: no x/y pair
    partners: list[tuple[float, float, int, float]] = []
    if only_partner or whirl_like:
        seeds = _non_harmonic_lines(s.power, s.peak_idx, df, f_best, s.snr_level)
        partners = _combination_partners(s.power, s.logp, df, s.floor, f_best, seeds, s.c_lo, s.c_hi, 0.45 * s.fs,
                                         s.sidebands)
    if only_partner and not partners:
        # a stated range whose one line lies at twice the whirl's frequency (excluded by _ranked as its 2nd
        # harmonic): the running speed's 1X may sit beside that harmonic, inside its main lobe
        hidden = _hidden_1x(s.x, s.spec, s.fs, df, s.k_top, s.f_top, s.c_lo, s.c_hi)
        if hidden is None:
            raise _no_line_in_range(s)
        return _Choice(first, hidden[0], f_best, f_partner=hidden[0], warnings=[hidden[1]])
    if not partners:
        half = _half_speed_whirl(s.spec, df, families)
        return _Choice(families[0], families[0].f_hz, f_best, warnings=[] if half is None else [half])
    whip_hz = refine_line_hz(s.x, s.fs, f_best, iterations=2)
    if abs(whip_hz - f_best) > 2 * df:
        whip_hz = f_best
    om, score, n_lines, r1 = partners[0]
    f_partner = _refine_partner(s.x, s.fs, df, s.power, s.floor, om, whip_hz, s.sidebands)
    warnings: list[str] = [Note("speed_from_whirl_partner", whirl_cpm=60 * whip_hz, ratio_x=whip_hz / f_partner,
                                n_lines=n_lines, speed_rpm=60 * f_partner)]
    weak_1x = r1 < cfg.SPEED_PARTNER_CLEAR_SNR
    close = len(partners) > 1 and partners[1][1] >= cfg.SPEED_PARTNER_RIVAL_REL * score
    # Ω ± ω spans the same lattice mΩ + kω as Ω: a runner-up one whirl frequency away with the stronger
    # own 1X line may be the running speed whatever the scores say
    shifted = [p for p in partners[1:] if abs(abs(p[0] - om) - whip_hz) <= 2 * cfg.SPEED_PARTNER_TOL_BINS * df
               and p[3] > r1]
    # a lattice that leaves more of the record's lines unexplained than it explains (a score ≤ 0) is no evidence
    # (docs/features.md, "Measurements behind the speed estimate's thresholds")
    unexplained = not score > 0
    if weak_1x or close or shifted or unexplained:
        why = (f"its own 1X line is {'not seen' if r1 == 0 else f'only {10 * np.log10(r1):.0f} dB above the noise'}"
               if weak_1x else
               f"{60 * partners[1][0]:.1f} r/min explains the combination lines almost as well" if close else
               f"{60 * shifted[0][0]:.1f} r/min, one whirl frequency away, spans the same combination lines and "
               "has the stronger 1X line" if shifted else
               "its lattice leaves more of the spectrum's lines unexplained than it explains")
        warnings.append(Note(
            "speed_estimate_ambiguous", detail=f"{60 * f_partner:.1f} r/min chosen from the combination lines of a "
            f"whirl / whip at {60 * whip_hz:.1f} cpm, but {why}; give speed_rpm or keyphasor_times_s"))
    return _Choice(first, f_partner, f_best, whip_hz=whip_hz, f_partner=f_partner, warnings=warnings)


def _ambiguous(warning: str) -> bool:
    """Whether ``warning`` is an ambiguous-estimate note (by its code, not its words)."""
    return getattr(warning, "code", None) == "speed_estimate_ambiguous"


def _foreign_lines_warning(s: _Spectrum, choice: _Choice) -> str | None:
    """The warning when lines that are not harmonics of the chosen speed stand out: peaks above
    ``SPEED_FOREIGN_MIN_SNR`` × the noise and ``SPEED_FOREIGN_MIN_REL`` of the largest line (less those on the
    lattice of a whirl the speed came from), and, unless a family above a whirl was taken, the weak lines above
    it that could be the running speed if the chosen one were a whirl (:func:`_weak_lines_above`)."""
    f = choice.f_hz
    foreign = _non_harmonic_lines(s.power, s.peak_idx, s.df, f, max(cfg.SPEED_FOREIGN_MIN_SNR * s.floor,
                                                                    cfg.SPEED_FOREIGN_MIN_REL ** 2 * s.p_max))
    if choice.whip_hz is not None:
        foreign = [g for g in foreign if not _on_lattice(g, f, choice.whip_hz, s.df)]
    elif choice.switched is None:
        foreign += [g for g in _weak_lines_above(s.power, s.df, s.floor, f, s.c_hi, s.sidebands) if g not in foreign]
    if not foreign:
        return None
    return Note("speed_estimate_ambiguous", detail=f"{60 * f:.1f} r/min chosen, but the lines at "
            f"{', '.join(f'{60 * g:.0f}' for g in foreign[:4])} cpm are not its harmonics (two independent "
            "frequencies: oil whirl / whip or a sub-harmonic, with the running speed possibly elsewhere); "
            "give speed_rpm or keyphasor_times_s")


def _comb_stage(s: _Spectrum, families: list[_Family], choice: _Choice) -> tuple[float, list[str]]:
    """The speed read off the chosen family's harmonic comb: period-n motion (:func:`_period_n`; period 3 switches
    to three times the speed, period 4 … ``SPEED_PERIOD_MAX_N`` is flagged), a rival family with the same lines
    present and ≥ 0.8 of the amplitude, or a larger family at twice the speed (period-2 motion and a 2X-dominated
    machine look alike) — each a warning. Returns the speed and the warnings."""
    f_best, df = choice.f_hz, s.df
    warnings: list[str] = []
    rivals = [c for c in families if c.f_hz != f_best and c.n_present > 0]
    period_n, strength = (_period_n(s.power, s.logp, df, f_best, s.snr_level, s.c_hi, s.sidebands)
                          if choice.switched is None else (0, 0))
    switch = period_n == 3 and strength == 2        # the only period read as the speed (see _period_n)
    if strength and not switch:
        warnings.append(Note(
            "speed_estimate_ambiguous", detail=f"{60 * f_best:.1f} r/min chosen, but its {period_n}X line stands above its "
            f"{period_n - 1}X and {period_n + 1}X, as the running speed's 1X does in period-{period_n} motion (then "
            f"{60 * f_best:.1f} cpm is a 1/{period_n}X sub-harmonic); if the machine runs at "
            f"{60 * period_n * f_best:.1f} r/min give speed_rpm or keyphasor_times_s"))
    if switch:
        # never a sub-harmonic: the comb's 3X and 6X stand out, so f_best is a 1/3X
        warnings.append(Note(
            "speed_estimate_ambiguous", detail=f"{60 * period_n * f_best:.1f} r/min chosen over {60 * f_best:.1f} r/min: the "
            f"lines at {period_n} and {2 * period_n} times {60 * f_best:.1f} cpm stand above their neighbours, the "
            f"signature of period-{period_n} motion (a 1/{period_n}X sub-harmonic with its 2/{period_n}X, "
            f"{period_n + 1}/{period_n}X …); if the machine runs at {60 * f_best:.1f} r/min give speed_rpm or "
            "keyphasor_times_s"))
        f_best = period_n * f_best
    elif rivals and rivals[0].n_present == choice.family.n_present and \
            rivals[0].amp_present >= 0.8 * choice.family.amp_present:
        warnings.append(Note(
            "speed_estimate_ambiguous", detail=f"{60 * f_best:.1f} r/min chosen over {60 * rivals[0].f_hz:.1f} "
            "r/min (similar harmonic content); give speed_rpm or keyphasor_times_s if this is wrong"))
    elif double_rival := [c for c in _doubles(families, f_best, choice.family.n_present, df)
                          if _hann_amplitude_at(s.power, c.f_hz, df) > _hann_amplitude_at(s.power, f_best, df)]:
        # period-2 motion (a 1/2X with its 1.5X, 2.5X …) and a machine whose 2X is its largest line
        # give the same spectrum: the larger line at twice the speed explains as many lines
        warnings.append(Note(
            "speed_estimate_ambiguous", detail=f"{60 * f_best:.1f} r/min chosen, but the larger line family at "
            f"{60 * double_rival[0].f_hz:.1f} cpm explains as many lines: if that is the running speed, the "
            f"{60 * f_best:.1f} cpm line is a 1/2X sub-harmonic (period-2 motion); give speed_rpm or "
            "keyphasor_times_s"))
    return f_best, warnings


def _refined_speed(s: _Spectrum, f_best: float, choice: _Choice) -> tuple[float, list[str]]:
    """``f_best`` refined (:func:`refine_line_hz`) on the strongest of its 1X–3X lines below 0.45 × fs, in the
    four channels that carry it most (after a switch above a whirl: not on a line the whirl's harmonics overlap).
    Keeps the interpolated peak, with a warning, when the refinement wanders off by more than two bins."""
    df, fs = s.df, s.fs
    harmonics = [m for m in (1, 2, 3) if m * f_best < 0.45 * fs]
    if choice.switched is not None:
        # not on a line the whirl's own harmonics overlap (its 2nd harmonic sits next to a 1X, ...)
        f_w = choice.f_first
        harmonics = [m for m in harmonics if abs(m * f_best - round(m * f_best / f_w) * f_w) > 2.5 * df] or [1]
    h = max(harmonics, key=lambda m: _hann_amplitude_at(s.power, m * f_best, df))
    k_h = int(round(h * f_best / df))
    strongest = np.argsort(-np.abs(s.spec[:, k_h]))[:4]       # the channels that carry the line
    f = refine_line_hz(s.x[strongest], fs, h * f_best) / h
    if abs(f - f_best) > 2 * df:
        return f_best, [Note("speed_not_converged", speed_rpm=60 * f_best)]
    return f, []


def _whirling_1x_warning(s: _Spectrum, f: float) -> str | None:
    """The warning when the chosen speed's 1X is the largest line and whirls in nearly circular orbits (backward /
    forward below ``SPEED_WHIRL_MAX_BACKWARD``) while a running speed above it is still possible: a lone whip
    family with no line of the running speed looks exactly like a machine running at the whip frequency."""
    k_top = s.k_top
    if not (abs(k_top * s.df - f) <= 1.5 * s.df and s.c_hi >= f / cfg.SPEED_SUBSYNC_MAX_RATIO):
        return None
    circ = _circular_fraction(s.spec, k_top)
    if not circ < cfg.SPEED_WHIRL_MAX_BACKWARD:
        return None
    return Note("speed_estimate_ambiguous", detail=f"{60 * f:.1f} r/min chosen, but its 1X line, the largest, whirls in "
            f"nearly circular orbits (backward / forward {circ:.3f}), the signature of oil whirl / whip; if the "
            f"machine runs above {60 * f / cfg.SPEED_SUBSYNC_MAX_RATIO:.0f} r/min this is the whip and the running "
            "speed's own line is hidden: give speed_rpm, speed_range_rpm or keyphasor_times_s")


def _flat_comb_warning(s: _Spectrum, f: float) -> str | None:
    """The warning when the comb of ``f`` is as flat as a sub-harmonic's: its 2X … ``SPEED_FLAT_COMB_ORDER`` X are
    all genuine lines (:func:`_line_amplitude`), each at least ``SPEED_FLAT_COMB_MIN_REL`` of its 1X.

    A running speed's harmonics come from the bearings' and the coupling's nonlinearity and fall off with the
    order (a flexible coupling's 2X may exceed the 1X, but its 3X, 5X do not follow); in period-n motion the
    1/nX sub-harmonic's comb k/nX holds the running speed's own 1X, 2X among comparable lines, and where no
    line of it stands out of the comb (:func:`_period_n`) nothing else tells it from a machine running at 1/n
    of the speed."""
    order = cfg.SPEED_FLAT_COMB_ORDER
    if order * f >= 0.45 * s.fs:
        return None
    a = [_line_amplitude(s.power, s.logp, m * f, s.df, s.snr_level, s.sidebands) for m in range(1, order + 1)]
    weakest = min(a[1:])
    if not (a[0] > 0 and weakest >= cfg.SPEED_FLAT_COMB_MIN_REL * a[0]):
        return None
    return Note("speed_estimate_ambiguous", detail=f"{60 * f:.1f} r/min chosen, but its 2X–{order}X lines all lie within "
            f"{-20 * np.log10(weakest / a[0]):.0f} dB of its 1X, a comb as flat as a 1/nX sub-harmonic's in period-n "
            f"motion (a running speed's harmonics fall off faster); if the machine runs at a multiple of "
            f"{60 * f:.1f} r/min give speed_rpm or keyphasor_times_s")


def _estimate_speed_hz(data: np.ndarray, fs: float,
                       speed_range_hz: tuple[float, float] | None = None) -> tuple[float, list[str]]:
    """Running speed (Hz) from the waveforms: the refined spectral line of 1X (see :func:`estimate_speed_hz`).

    Parameters
    ----------
    data : ndarray, shape (n_channels, n_points)
        x/y displacements, µm.
    fs : float
        Sample rate, Hz.
    speed_range_hz : (float, float), optional
        The running speed is known to lie in [min, max] Hz (the machine's nominal speed, e.g.
        a grid-synchronous generator): only candidates in that range are considered. Raises
        ``ValueError`` when none has a line there.

    Returns
    -------
    speed_hz, warnings

    Notes
    -----
    The summed Hann power spectrum of all channels is searched for its largest peaks in
    ``SPEED_SEARCH_RPM`` (and with 3X below 0.75 × Nyquist). Each peak ``f_p`` and its
    sub-multiples ``f_p/2``, ``f_p/3`` is a candidate running speed if it has a line of its
    own; candidates are ranked by how many of their 1X, 2X, 3X lines are present (a line is
    present when it stands ``SPEED_LINE_MIN_SNR`` above the median spectrum and its amplitude
    is at least ``SPEED_HARMONIC_MIN_REL`` of the largest line), then by the summed
    amplitude of those lines. So a dominant 2X (the two-pole generator's
    twice-per-revolution) or a strong sub-synchronous whirl line is not taken for 1X as
    long as the true 1X shows at least one harmonic. The winning line (its strongest
    harmonic) is refined by :func:`refine_line_hz`. Period-2 motion (a 1/2X line) and a
    2X-dominated signal can look alike to any spectral method: a warning is given when the
    two best candidates have the same number of lines and amplitudes within 20 %.

    A running speed whose 1X is the largest line and whose orbits there are nearly circular
    (backward / forward component below ``SPEED_WHIRL_MAX_BACKWARD``, the signature of a
    self-excited whirl or whip) is flagged ambiguous when a running speed above it (at least
    ``1 / SPEED_SUBSYNC_MAX_RATIO`` times faster) is still possible: a lone whip family with no
    line of the running speed looks exactly like a machine running at the whip frequency.

    The stages, in order: :func:`_spectrum`, :func:`_seed_bins` and :func:`_candidate_families`,
    :func:`_ranked`, :func:`_whirl_stage`, :func:`_foreign_lines_warning`, then (unless the speed came from a
    whirl's combination lines) :func:`_comb_stage` and :func:`_refined_speed` and :func:`_hidden_1x`, and last
    :func:`_whirling_1x_warning` or :func:`_flat_comb_warning`, and the non-synchronous largest line.
    """
    s = _spectrum(data, fs, speed_range_hz)
    ranged = speed_range_hz is not None
    families, only_partner = _ranked(s, _candidate_families(s, _seed_bins(s, ranged)), ranged)
    choice = _whirl_stage(s, families, only_partner)
    warnings = choice.warnings
    if (foreign := _foreign_lines_warning(s, choice)) is not None:
        warnings.append(foreign)
    if choice.f_partner is not None:
        f = choice.f_partner
    else:
        f_best, comb_warnings = _comb_stage(s, families, choice)
        f, refine_warnings = _refined_speed(s, f_best, choice)
        warnings += comb_warnings + refine_warnings
        hidden = _hidden_1x(s.x, s.spec, fs, s.df, s.k_top, f, s.c_lo, s.c_hi)
        if hidden is not None:
            f, note = hidden
            warnings = [w for w in warnings if not _ambiguous(w)] + [note]
    if choice.f_partner is None and not any(_ambiguous(w) for w in warnings):
        last = (_whirling_1x_warning(s, f) if choice.switched is None else None) or _flat_comb_warning(s, f)
        if last is not None:
            warnings.append(last)
    k_top = s.k_top
    top_order = k_top * s.df / f
    if abs(top_order - round(top_order)) > 0.05 or round(top_order) == 0:
        warnings.append(Note("non_synchronous_dominant", line_cpm=60 * k_top * s.df, order=top_order))
    return f, warnings


def shaft_angle(rec, data: np.ndarray, estimate: tuple[float, list[str]] | None = None) -> ShaftAngle:
    """Speed, analysed segment and shaft angle for a recording.

    Parameters
    ----------
    rec : Recording
    data : ndarray, shape (n_channels, n_points)
        x/y displacements in µm (to estimate the speed when neither a keyphasor nor ``speed_rpm`` is
        given, and to lock a given ``speed_rpm`` to the signal's synchronous lines, :mod:`._speed_lock`).
    estimate : (speed_rpm, warnings), optional
        The speed estimated elsewhere (a caller that chose among :func:`speed_alternatives_rpm`), used
        instead of :func:`estimate_speed_hz` with its warnings when neither a keyphasor nor ``speed_rpm``
        is given.
    """
    fs = rec.sample_rate_hz
    n = data.shape[1]
    warnings: list[str] = []
    if rec.keyphasor_times_s is not None:
        t_end = (n - 1) / fs
        kp = pulses_in_record(rec.keyphasor_times_s, n, fs)
        if kp.size < 2:
            raise ValueError(
                f"keyphasor_times_s: {kp.size} pulse(s) fall inside the record (0 to {t_end:.4g} s); the pulse times "
                "must be on the samples' clock (first sample at t = 0)")
        fault = keyphasor_fault(kp)
        if fault is not None:
            # the pulses cannot be tracked: the orders are tracked at a steady speed instead — the one stated, else
            # the sound intervals' period (locked to the signal's synchronous lines), else the signal's own estimate —
            # with phases relative to the first sample
            rpm_steady = rec.speed_rpm if rec.speed_rpm is not None else \
                None if fault.period_s is None else 60.0 / fault.period_s
            bare = [replace(c, slow_roll_um_pp=None) for c in rec.channels]   # keyphasor-referenced: not here
            steady = shaft_angle(replace(rec, channels=bare, keyphasor_times_s=None, speed_rpm=rpm_steady), data)
            source = ("speed_rpm" if rec.speed_rpm is not None else "estimated from the signal" if rpm_steady is None
                      else "the sound pulse intervals' period, locked to the signal")
            note = Note("keyphasor_not_used", fault=fault.describe(), speed_rpm=steady.speed_rpm, source=source)
            # a speed read from the sound pulse intervals was not given by the user: say where it came from
            label = KEYPHASOR_INTERVALS if rec.speed_rpm is None and rpm_steady is not None else steady.source
            return replace(steady, source=label, warnings=[note, *steady.warnings])
        periods = np.diff(kp)
        n_revs = int(kp.size - 1)
        rpm = 60.0 * n_revs / float(kp[-1] - kp[0])
        if n_revs < cfg.MIN_REVS:
            raise _too_short(n_revs, rpm, fs, n, "from the keyphasor pulses inside the record")
        spr_min = fs * float(periods.min())
        if spr_min < cfg.MIN_SAMPLES_PER_REV:
            raise _too_slow_sampling(spr_min, fs, 1.0 / float(periods.min()))
        variation = float(np.max(np.abs(periods / periods.mean() - 1.0)))
        if variation > cfg.SPEED_VARIATION_WARN:
            warnings.append(Note("speed_varies", variation_pct=100 * variation))
        if rec.speed_rpm is not None and abs(rec.speed_rpm / rpm - 1) > 0.01:
            warnings.append(Note("speed_disagrees_keyphasor", given_rpm=rec.speed_rpm, speed_rpm=rpm))
        t = np.arange(n) / fs
        start = int(np.searchsorted(t, kp[0], side="left"))
        stop = int(np.searchsorted(t, kp[-1], side="left"))
        theta = 2 * np.pi * np.interp(t[start:stop], kp, np.arange(kp.size, dtype=float))
        return ShaftAngle(rpm, "keyphasor", start, stop, theta, n_revs, kp[:-1].copy(), spr_min, warnings)

    if rec.speed_rpm is not None:
        f1, source = rec.speed_rpm / 60.0, "given"
        f_lock = locked_speed_hz(data, fs, f1)
        if f_lock is not None and abs(f_lock / f1 - 1.0) > cfg.SPEED_LOCK_MIN_REL:
            if abs(f_lock / f1 - 1.0) > cfg.SPEED_MISMATCH_WARN:
                warnings.append(Note("speed_off_signal", given_rpm=rec.speed_rpm, off_pct=100 * (f1 / f_lock - 1),
                                     speed_rpm=60 * f_lock))
            f1 = f_lock
    else:
        if estimate is not None:
            f1, est_warn = estimate[0] / 60.0, list(estimate[1])
        else:
            rng = rec.speed_range_rpm
            f1, est_warn = estimate_speed_hz(data, fs, None if rng is None else (rng[0] / 60.0, rng[1] / 60.0))
        warnings.extend(est_warn)
        source = "estimated"
    spr = fs / f1
    n_revs = int(np.floor(n / spr + 1e-9))
    if spr < cfg.MIN_SAMPLES_PER_REV or n_revs < cfg.MIN_REVS:
        err = _too_slow_sampling(spr, fs, f1) if spr < cfg.MIN_SAMPLES_PER_REV else \
            _too_short(n / spr, 60 * f1, fs, n, "speed " + source)
        doubt = next((w for w in warnings if _ambiguous(w)), None)
        if doubt is not None:
            # the limit may be the estimate's fault (a 1/nX read as the speed): say so, not only "record longer"
            raise ValueError(f"{err}. But the running speed was estimated and is in doubt — {doubt}") from None
        raise err
    stop = min(n, int(np.ceil(n_revs * spr - 1e-9)))
    theta = (2 * np.pi * f1 / fs) * np.arange(stop)
    rev_times = np.arange(n_revs) / f1
    return ShaftAngle(60.0 * f1, source, 0, stop, theta, n_revs, rev_times, spr, warnings)
