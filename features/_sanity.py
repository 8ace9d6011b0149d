"""Physics sanity checks of a recording, before any verdict (issue 15, item 1).

Each check returns :class:`SanityFinding` entries with a specific message saying what to
check. ``level`` says what the finding does to a verdict:

- ``"fail"``: the recording is physically impossible or unusable as given (flat, all-zero or
  clipped channels, an orbit larger than the bearing's diametral clearance, a DC position no
  proximity probe can read, reverse 1X whirl at every bearing). A verdict is ``inconclusive``.
- ``"warn"``: plausible but suspicious (reverse 1X whirl at one bearing, no synchronous
  vibration above the noise at one bearing, a 1X or 2X that is one signal common to every probe, a keyphasor
  pulse train with missing or extra pulses, an orbit beyond the clearance only through a few isolated samples). A
  verdict is at best ``uncertain``.

A DC position outside the clearance circle is not a finding: DC-coupled probes read their
gap, not the shaft centre, and no feature uses the mean (``features.evidence`` says so).

Too few revolutions or samples per revolution (3X near Nyquist) are refused earlier, with a
``ValueError`` (HTTP 422), by :func:`features.extract_features`.
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from rotordiag.core.notes import Length as L
from rotordiag.core.notes import Measured
from rotordiag.core.reasons import DEFAULT_VARIANT, FAIL, WARN, code_info, require_code

from ._common_mode import COMMON_MODE_MIN_PROBES, CommonMode, common_mode
from ._keyphasor import keyphasor_fault, pulses_in_record
from ._recording import Recording
from ._speed import estimate_speed_hz

__all__ = ["SanityFinding", "check_recording", "FAIL", "WARN", "COMMON_MODE_MIN_SHARE",
           "PROBE_RANGE_UM", "MAX_DC_UM", "ORBIT_CLEARANCE_MARGIN", "CLIP_MIN_FRACTION"]


#: a peak-to-peak motion beyond this (µm) is outside the linear range of any proximity probe
#: (the common 8 mm probe is linear over about 2 mm; 2 mm pk-pk leaves no room): check units
PROBE_RANGE_UM = 2000.0
#: a mean reading beyond this (µm, 10 mm) is not a gap any proximity probe reads: check units / scale
MAX_DC_UM = 10_000.0
#: a journal cannot move further than the diametral clearance 2c; allow this factor for
#: shaft runout, probe gain error and noise before calling an orbit impossible
ORBIT_CLEARANCE_MARGIN = 1.1
#: ... plus the peak-to-peak that the channels' broadband noise can add: 2·k·σ, with k the Gaussian quantile that
#: one of the record's samples exceeds with this probability (white noise at 15 dB SNR on an oil-whip orbit at
#: 0.9 × 2c reads 1.2-1.3 × 2c pk-pk)
ORBIT_NOISE_FALSE_ALARM = 1e-3
#: a channel whose samples sit at its own extreme value this often is clipped …
CLIP_MIN_FRACTION = 0.02
#: … provided that is this many times what a quantised sine would give (sampling resolution)
CLIP_EXCESS = 3.0
#: a clipped-looking channel whose samples at the extreme lie this much in one unbroken stretch is a dropout (the
#: acquisition holding one value: a loose connector, lost samples), not clipping, which recurs every revolution
DROPOUT_MIN_SHARE = 0.9
#: with no 1X at the given speed, a running-speed line read from the signal this far from it (relative) is named
#: in the message, with the sample rate that would put it at the given speed
SPEED_MISMATCH_MIN_REL = 0.02
#: 1X whirl index (F − R)/(F + R) below this counts as clearly reverse
REVERSE_WHIRL_INDEX = -0.2
#: a 1X zero-to-peak amplitude below this multiple of its noise-equivalent amplitude is "in the noise"
SYNC_MIN_SNR = 3.0
#: a sub-synchronous share of the vibration power (``b{n}_subsync_frac``) above this at a bearing reads as oil
#: whirl / whip dominating it
WHIRL_DOMINANT_FRACTION = 0.5
#: a sample further than this fraction of its channel's 1–99 % range from the median of its five neighbours is a
#: spike (:func:`spike_samples`) …
SPIKE_MIN_REL = 0.35
#: … when such samples are at most this fraction of the record
SPIKE_MAX_FRACTION = 0.005
#: the orders whose common mode is judged (:func:`_common_mode_checks`): the 1X and 2X vectors the misalignment
#: evidence rests on (a generator rotor's 3X can be nearly common to bearings 1–3 of a healthy machine)
COMMON_MODE_ORDERS = (1, 2)
#: the share of an order's power across the probes that one signal common to all explains
#: (``features._common_mode.common_mode_share``) from which the order is no shaft motion, by the number of probes
#: judged (at least ``COMMON_MODE_MIN_PROBES``, on both sides of the coupling): above every share a shaft's own
#: motion reached on held-out simulated plants (docs/features.md, "Measurements behind the speed estimate's
#: thresholds")
COMMON_MODE_MIN_SHARE: dict[int, float] = {COMMON_MODE_MIN_PROBES: 0.95, 8: 0.85}


@dataclass(frozen=True)
class SanityFinding:
    """One failed or suspicious check.

    Attributes
    ----------
    code : str
        Stable identifier, one of the catalogue's (:mod:`rotordiag.core.reasons`; any other is refused).
    level : str
        ``"fail"`` or ``"warn"``.
    values : mapping
        The catalogue template's fields, exactly (a length as :class:`~rotordiag.core.notes.Length`).
    bearing : int or None
    variant : str
        Which of the code's templates (``"default"`` unless the code has named cases).
    """

    code: str
    level: str
    values: Mapping[str, Any] = field(default_factory=dict, hash=False)
    bearing: int | None = None
    variant: str = DEFAULT_VARIANT

    def __post_init__(self) -> None:
        require_code(self.code, self.level)
        object.__setattr__(self, "_message", code_info(self.code).message(self.variant, self.values))

    @property
    def message(self) -> Measured:
        """What was found and what to check, in words (µm; ``.render("mil")`` for mils)."""
        return self._message  # type: ignore[attr-defined]

    def to_dict(self) -> dict:
        return {"code": self.code, "level": self.level, "message": self.message, "bearing": self.bearing}


def _channel_checks(rec: Recording) -> list[SanityFinding]:
    out: list[SanityFinding] = []
    # every channel's extremes and the share of its samples at them, in one pass over all channels (the same
    # floats as channel by channel: min, max and counts are exact; |d|'s maximum is max(max d, −min d))
    data = np.stack([ch.data_um for ch in rec.channels])
    lows, highs = data.min(axis=1), data.max(axis=1)
    scales = np.maximum(np.maximum(highs, -lows), 1.0)
    tols = 1e-9 * scales
    n = data.shape[1]
    at_low = np.count_nonzero(data <= (lows + tols)[:, None], axis=1) / n
    at_high = np.count_nonzero(data >= (highs - tols)[:, None], axis=1) / n
    for i, ch in enumerate(rec.channels):
        d = data[i]
        where = {"bearing": ch.bearing, "angle_deg": ch.angle_deg}
        lo, hi = float(lows[i]), float(highs[i])
        ptp = hi - lo
        scale = float(scales[i])
        if lo == 0 and hi == 0:
            out.append(SanityFinding("zero_channel", FAIL, where, ch.bearing))
            continue
        if ptp <= 1e-9 * scale:
            out.append(SanityFinding("flat_channel", FAIL, {**where, "level": L(float(d[0]), ".6g")}, ch.bearing))
            continue
        tol = float(tols[i])
        frac = max(float(at_low[i]), float(at_high[i]))
        if frac >= CLIP_MIN_FRACTION:
            levels = np.unique(d)
            q = float(np.min(np.diff(levels))) if levels.size > 1 else ptp
            # fraction of a sine's samples within one quantisation step of its peak: arccos(1 − 2q/ptp)/π
            expected = float(np.arccos(max(-1.0, 1.0 - 2.0 * q / ptp)) / np.pi)
            if frac > CLIP_EXCESS * expected:
                at = "maximum" if at_high[i] >= at_low[i] else "minimum"
                stretch = _one_stretch(d >= hi - tol if at == "maximum" else d <= lo + tol)
                if stretch is not None:
                    fs = rec.sample_rate_hz
                    out.append(SanityFinding(
                        "dropout", FAIL, {**where, "level": L(hi if at == "maximum" else lo, ".6g"),
                                          "duration_ms": 1e3 * (stretch[1] - stretch[0]) / fs,
                                          "start_s": stretch[0] / fs, "stop_s": stretch[1] / fs}, ch.bearing))
                    continue
                out.append(SanityFinding(
                    "clipped_channel", FAIL, {**where, "share_pct": 100 * frac, "extreme": at,
                                              "level": L(hi if at == "maximum" else lo, ".6g")}, ch.bearing))
    return out


def _one_stretch(at_extreme: np.ndarray) -> tuple[int, int] | None:
    """(start, stop) sample of the longest unbroken run of ``at_extreme`` when it holds at least
    :data:`DROPOUT_MIN_SHARE` of its true samples, else None."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], at_extreme.view(np.int8), [0]))))
    starts, stops = edges[::2], edges[1::2]
    k = int(np.argmax(stops - starts))
    if stops[k] - starts[k] < DROPOUT_MIN_SHARE * int(np.count_nonzero(at_extreme)):
        return None
    return int(starts[k]), int(stops[k])


def noise_peak_to_peak_um(noise_rms_um: Iterable[float], n_samples: int,
                         false_alarm: float = ORBIT_NOISE_FALSE_ALARM) -> float:
    """Peak-to-peak that white noise of the larger of ``noise_rms_um`` (σ, µm) adds to a record.

    2·k·σ, with k such that a Gaussian sample exceeds ±kσ with probability ``false_alarm``
    anywhere in ``n_samples`` samples (Bonferroni); 0 when σ is unknown."""
    from scipy.special import ndtri

    sigma = max((float(v) for v in noise_rms_um if np.isfinite(v)), default=0.0)
    if sigma <= 0 or n_samples < 1:
        return 0.0
    return 2.0 * float(-ndtri(false_alarm / (2.0 * n_samples))) * sigma


def spike_samples(signal: np.ndarray) -> np.ndarray:
    """Indices of isolated samples far off their neighbours (a glitch: electrical noise, a scratch, a dropout).

    A sample counts when it lies more than ``SPIKE_MIN_REL`` of the signal's 1–99 % range from the median of the
    five samples around it; a sampled sine never does (at 8 samples per revolution, the fewest the features accept,
    a peak lies 0.15 of the range from its neighbours' median). At most ``SPIKE_MAX_FRACTION`` of the record: more is
    no glitch."""
    from scipy.ndimage import median_filter

    x = np.asarray(signal, dtype=float)
    lo, hi = np.percentile(x, [1.0, 99.0])
    off = np.abs(x - median_filter(x, size=5, mode="nearest")) > SPIKE_MIN_REL * (hi - lo)
    idx = np.flatnonzero(off)
    return idx if idx.size <= SPIKE_MAX_FRACTION * x.size else np.empty(0, dtype=np.int64)


def _spike_finding(rec: Recording, b: int, x: np.ndarray, y: np.ndarray, limit: float) -> SanityFinding | None:
    """``spike`` when bearing ``b``'s orbit (``x``, ``y`` in µm) is beyond ``limit`` only because of isolated
    samples, else None."""
    ptp = max(float(np.ptp(x)), float(np.ptp(y)))
    bad = np.union1d(spike_samples(x), spike_samples(y))
    if bad.size == 0:
        return None
    keep = np.ones(x.size, dtype=bool)
    keep[bad] = False
    rest = max(float(np.ptp(x[keep])), float(np.ptp(y[keep])))
    if rest > limit:
        return None
    t = ", ".join(f"{i / rec.sample_rate_hz:.4g}" for i in bad[:5]) + (" …" if bad.size > 5 else "")
    return SanityFinding("spike", WARN, {"bearing": b, "n_samples": int(bad.size), "times_s": t,
                                         "orbit": L(ptp, ".4g"), "orbit_without": L(rest, ".4g")}, b)


def _amplitude_checks(rec: Recording, fr) -> list[SanityFinding]:
    out: list[SanityFinding] = []
    for b, det in sorted(fr.bearings.items()):
        x, y = rec.xy_um(b)
        ptp = max(float(np.ptp(x)), float(np.ptp(y)))
        c = float(det.clearance_um)
        units = sorted({ch.declared_as or ch.units for ch in rec.channels if ch.bearing == b})
        units_txt = "/".join(units)
        beyond = bool(np.isfinite(c) and c > 0 and ptp > ORBIT_CLEARANCE_MARGIN * 2 * c)
        noise_pp = noise_peak_to_peak_um(det.noise_rms_um, x.size) if beyond else 0.0
        limit = ORBIT_CLEARANCE_MARGIN * 2 * c + noise_pp
        spike = _spike_finding(rec, b, x, y, limit) if beyond and ptp > limit else None
        if spike is not None:
            out.append(spike)
        elif beyond and ptp > limit:
            values = {"bearing": b, "orbit": L(ptp, ".4g"), "ratio": ptp / (2 * c), "clearance_2c": L(2 * c, ".4g"),
                      "units": units_txt}
            noted = noise_pp > 0.01 * 2 * c
            out.append(SanityFinding("orbit_exceeds_clearance", FAIL,
                                     {**values, "noise": L(noise_pp)} if noted else values, b,
                                     "noise_allowance" if noted else DEFAULT_VARIANT))
        elif ptp > PROBE_RANGE_UM:
            out.append(SanityFinding("orbit_exceeds_probe_range", FAIL,
                                     {"bearing": b, "orbit": L(ptp, ".4g"), "probe_range": L(PROBE_RANGE_UM, "g"),
                                      "units": units_txt}, b))
        mean = np.array(det.mean_um)
        r = float(np.hypot(*mean))
        if r > MAX_DC_UM:
            out.append(SanityFinding("dc_implausible", FAIL, {"bearing": b, "mean": L(r, ".4g"), "units": units_txt}, b))
    return out


def _whirl_checks(fr) -> list[SanityFinding]:
    out: list[SanityFinding] = []
    reverse, judged = [], []
    for b, det in sorted(fr.bearings.items()):
        f1, r1 = abs(det.forward_um[0]), abs(det.reverse_um[0])
        noise = det.line_noise_um
        a1 = max(abs(det.x_coeffs_um[0]), abs(det.y_coeffs_um[0]))
        if noise is not None and np.all(np.isfinite(noise[:, 0])) and a1 < SYNC_MIN_SNR * float(np.max(noise[:, 0])):
            continue
        if f1 + r1 <= 0:
            continue
        judged.append(b)
        if (f1 - r1) / (f1 + r1) < REVERSE_WHIRL_INDEX:
            reverse.append(b)
    if len(judged) >= 2 and reverse == judged:
        out.append(SanityFinding("reverse_whirl_all", FAIL, {"bearings": ", ".join(map(str, reverse))}))
    else:
        for b in reverse:
            out.append(SanityFinding("reverse_whirl", WARN, {"bearing": b}, b))
    return out


def _signal_checks(rec: Recording, fr) -> list[SanityFinding]:
    weak = []
    for b, det in sorted(fr.bearings.items()):
        noise = det.line_noise_um
        if noise is None:
            continue
        a1 = np.abs(np.array([det.x_coeffs_um[0], det.y_coeffs_um[0]]))
        if np.all(a1 < SYNC_MIN_SNR * noise[:, 0]):
            weak.append(b)
    if weak and len(weak) == len(fr.bearings):
        values = dict(zip(fr.names, fr.values))
        whirl = [b for b in weak if float(values.get(f"b{b}_subsync_frac", np.nan)) > WHIRL_DOMINANT_FRACTION]
        mismatch = _speed_mismatch(rec, fr)
        speed = {} if mismatch is None else mismatch
        if whirl:
            order = float(values.get(f"b{whirl[0]}_subsync_peak_order", np.nan))
            near = f" near {order:.2f}X" if np.isfinite(order) else ""
            return [SanityFinding("no_sync_signal", FAIL,
                                  {"near": near, "bearings": ", ".join(map(str, whirl)), **speed}, None,
                                  "whirl" if mismatch is None else "whirl_speed")]
        return [SanityFinding("no_sync_signal", FAIL, speed, None,
                              "every_bearing" if mismatch is None else "every_bearing_speed")]
    return [SanityFinding("no_sync_signal", WARN, {"bearing": b}, b) for b in weak]


def _speed_mismatch(rec: Recording, fr) -> dict[str, float] | None:
    """With a given speed: the running speed the signal shows when it is more than :data:`SPEED_MISMATCH_MIN_REL`
    away from it, as the ``no_sync_signal`` template's values — a wrong ``speed_rpm``, or a sample rate stated k times
    the true one (every line then reads k times its frequency), told apart by the rate that would fit; else None."""
    if fr.speed_source != "given":
        return None
    fs = rec.sample_rate_hz
    try:
        f_hz, _ = estimate_speed_hz(rec.xy_all_um(), fs)
    except ValueError:
        return None
    ratio = 60.0 * f_hz / fr.speed_rpm
    if not abs(ratio - 1.0) > SPEED_MISMATCH_MIN_REL:
        return None
    return {"signal_rpm": 60.0 * f_hz, "ratio": ratio, "given_rpm": fr.speed_rpm, "fitting_rate_hz": fs / ratio,
            "sample_rate_hz": fs}


def common_mode_dominates(cm: CommonMode) -> bool:
    """Whether the common signal is the order (its share reaches :data:`COMMON_MODE_MIN_SHARE` for its probes)."""
    return cm.share >= COMMON_MODE_MIN_SHARE[max(m for m in COMMON_MODE_MIN_SHARE if m <= cm.n_probes)]


def _common_mode_checks(fr) -> list[SanityFinding]:
    """A 1X or 2X that reads the same amplitude and phase at every probe is no shaft motion (:mod:`._common_mode`):
    a warning when its share reaches :data:`COMMON_MODE_MIN_SHARE`. The verdict is given on the recording without it
    (``models.checks.common_mode``)."""
    out: list[SanityFinding] = []
    for k in COMMON_MODE_ORDERS:
        cm = common_mode(fr, k)
        if cm is None or not common_mode_dominates(cm):
            continue
        out.append(SanityFinding(
            f"common_mode_{k}x", WARN,
            {"amp": L(cm.amp_um_pp), "phase_lag_deg": cm.phase_lag_deg, "n_probes": cm.n_probes,
             "bearings": ", ".join(map(str, cm.bearings)), "share_pct": 100 * cm.share}))
    return out


def _keyphasor_checks(rec: Recording) -> list[SanityFinding]:
    if rec.keyphasor_times_s is None:
        return []
    takes = rec.keyphasor_takes
    trains = takes if takes is not None else (cast(np.ndarray, rec.keyphasor_times_s),)
    where = [", ".join(map(str, g)) for g in rec.acquisition_groups] if takes else [None]
    out = []
    for train, group in zip(trains, where):
        fault = keyphasor_fault(pulses_in_record(train, rec.n_points, rec.sample_rate_hz))
        if fault is None:
            continue
        out.append(SanityFinding("keyphasor_faulty", WARN, {"fault": fault.describe()}) if group is None else
                   SanityFinding("keyphasor_faulty", WARN, {"fault": fault.describe(), "bearings": group}, None,
                                 "take"))
    return out


def check_recording(rec: Recording, fr) -> tuple[SanityFinding, ...]:
    """Physics sanity checks of a recording and its extracted features.

    Parameters
    ----------
    rec : Recording
    fr : features.FeatureResult
        The result of ``extract_features(rec)``.

    Returns
    -------
    tuple of SanityFinding
        Empty when every check passes; ``fail`` findings first.
    """
    bad_channel = _channel_checks(rec)
    found = bad_channel + _amplitude_checks(rec, fr) + _keyphasor_checks(rec)
    if not bad_channel:   # a dead or clipped channel already explains odd whirl and missing 1X
        found += _signal_checks(rec, fr)
        if not any(f.code == "no_sync_signal" and f.level == FAIL for f in found):
            found += _common_mode_checks(fr) + _whirl_checks(fr)
    return tuple(sorted(found, key=lambda f: f.level != FAIL))
