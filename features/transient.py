"""Start-ups and coast-downs: order tracking and the data of the plots vibration engineers read (issue 46).

From a :class:`~rotordiag.features.Recording` whose speed changes:

- :func:`track_orders` — the 1X and 2X vectors of every probe per revolution (or per speed step), from the
  keyphasor when there is one, else along a speed tracked from the signal (:func:`track_speed`; phases then have
  no reference and are not reported as phase lags). Each revolution is a least-squares fit of
  ``c0 + Σ_k Re(C_k e^{jkθ})`` (with a linear drift of the gap across the revolution, :func:`_fit_steps`) over
  its own samples at the shaft angle θ interpolated linearly between the pulses (constant speed within a
  revolution), so the gap (DC) does not leak into the orders and noise is averaged over every sample.
- :func:`waterfall` and :func:`full_spectrum` — spectra of short windows against speed (a cascade), the full
  spectrum of a probe pair (x + jy: forward whirl at positive, reverse at negative frequencies).
- :func:`centreline` — the shaft centreline: each bearing's mean journal position per revolution.
- :func:`orbits_at` — the raw and 1X-filtered orbit of one revolution at chosen speeds.

Conventions (:data:`CONVENTIONS`, printed on every plot): amplitudes µm peak-to-peak; phase lag in degrees of the
order's own cycle, from the keyphasor mark to the next positive peak of the filtered signal (``A cos(kθ − φ)``,
0–360°, the same as :mod:`rotordiag.features` steady orders); probe angles and x/y as in the recording (degrees
from horizontal +x toward vertical +y, the shaft turning from +x toward +y; the reader mirrors a clockwise
machine so this holds, see ``features.reader``).

Recordings of a start-up are longer than a steady one: :data:`TRANSIENT_READ_LIMITS` is what the transient doors
read with (a 160-s start-up of 8 probes at 25.6 kHz; a longer file is refused by the reader, naming the limit).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from rotordiag.core.notes import speed_in_doubt

from . import _config as cfg
from ._recording import Recording
from ._speed import estimate_speed_hz
from .reader import ReadLimits

__all__ = [
    "CONVENTIONS", "conventions", "TRANSIENT_READ_LIMITS", "OrderTrack", "SpeedTrack", "Waterfall", "Centreline", "Orbit",
    "track_orders", "track_speed", "waterfall", "full_spectrum", "centreline", "orbits_at", "check_pulses",
]

def conventions(units: str = "um") -> str:
    """The conventions of the transient data and plots, lengths in ``units`` (``um`` or ``mil``)."""
    u = "mil" if units == "mil" else "µm"
    return (f"amplitude {u} pk-pk; phase lag ° (keyphasor mark → next positive peak, 0–360°, in the order's own "
            "cycle); x horizontal, y vertical up, probe angles ° from +x toward +y, viewed from the end where the "
            "shaft turns +x → +y (counter-clockwise; the reader mirrors a clockwise view)")


CONVENTIONS = conventions("um")
#: 4 Mi points per channel: 160 s at 25.6 kHz, 8 probes (256 MiB as float64).
TRANSIENT_READ_LIMITS = ReadLimits(max_points=4 * 2**20, max_file_bytes=768 * 2**20, max_hdf5_bytes=512 * 2**20,
                                   max_keyphasor_pulses=200_000)
#: A pulse interval more than this factor off the geometric mean of its two neighbours is no speed change
#: (a missed pulse doubles an interval, an extra one halves it; a run-up changes the period smoothly).
PULSE_RATIO_MAX = 1.5
#: The keyphasor counts as stopped when the record runs on past its last pulse for this many periods.
PULSE_STOP_PERIODS = 2.5
#: Speed reversal: the (median-smoothed) speed falls back from its running maximum (run-up; rises from its running
#: minimum in a coast-down) by more than this fraction of the speed range.
REVERSAL_FRACTION = 0.05
#: The orders of a step are not read where the RMS of what the fit leaves exceeds this × the orders' RMS.
NONSYNC_MAX_RATIO = 1.0
#: ... or where the vector's second difference between steps exceeds this fraction of it.
VECTOR_JUMP_MAX = 0.25
#: ... and a vector is read only inside a run of at least this many readable steps.
MIN_READABLE_RUN = 5
#: Windows of the speed tracked from the signal, s, and their hop.
SPEED_WINDOW_S = 1.0
SPEED_HOP_S = 0.5
#: Neighbouring windows' speeds further apart than this (relative) are a harmonic confusion, not acceleration.
SPEED_JUMP_MAX = 0.15


def _probe_names(rec: Recording) -> tuple[tuple[int, float], ...]:
    return tuple((c.bearing, c.angle_deg) for c in rec.channels)


@dataclass(frozen=True)
class SpeedTrack:
    """Running speed tracked from the signal (no keyphasor).

    Attributes
    ----------
    time_s, speed_rpm : ndarray, shape (n_windows,)
        Window centres and the speed estimated there (NaN where the estimate failed).
    in_doubt : ndarray of bool
        Windows whose estimate was ambiguous, failed, or jumps against its neighbours (a harmonic read as 1X).
    notes : list of str
    """

    time_s: np.ndarray
    speed_rpm: np.ndarray
    in_doubt: np.ndarray
    notes: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class OrderTrack:
    """1X/2X vectors against speed.

    Attributes
    ----------
    time_s, speed_rpm : ndarray, shape (n_steps,)
        Mid time and mean speed of each revolution (or speed step).
    probes : tuple of (bearing, angle_deg)
    orders : tuple of int
    vectors_um : complex ndarray, shape (n_steps, n_probes, n_orders)
        Zero-to-peak complex amplitude ``C = A e^{−jφ}`` (signal ``A cos(kθ − φ)``).
    dc_um : ndarray, shape (n_steps, n_probes)
        Mean probe reading over each step (the gap, for the centreline).
    phase_referenced : bool
        True with a keyphasor; without one the phases are relative to an integrated angle and are not phase lags.
    speed_source : str
        ``"keyphasor"`` or ``"signal"``.
    in_doubt : ndarray of bool, shape (n_steps,)
        Steps where the tracked speed is in doubt (no keyphasor only).
    kind : str
        ``"run-up"``, ``"coast-down"`` or ``"steady"``.
    sample_bounds : ndarray of int, shape (n_steps + 1,)
        Sample index where each step starts (and the last one ends).
    """

    time_s: np.ndarray
    speed_rpm: np.ndarray
    probes: tuple[tuple[int, float], ...]
    orders: tuple[int, ...]
    vectors_um: np.ndarray
    dc_um: np.ndarray
    phase_referenced: bool
    speed_source: str
    in_doubt: np.ndarray
    kind: str
    sample_bounds: np.ndarray
    notes: list[str] = field(default_factory=list)
    conventions: str = CONVENTIONS
    #: (n_steps, n_probes, n_orders): the vector cannot be read — what the fit leaves exceeds
    #: ``NONSYNC_MAX_RATIO`` × the orders' RMS, or it jumps by more than ``VECTOR_JUMP_MAX`` between steps
    nonsync: np.ndarray | None = None
    residual_rms_um: np.ndarray | None = None

    def readable(self) -> np.ndarray:
        """(n_steps, n_probes, n_orders) mask of the vectors that can be read: speed not in doubt, the order neither
        swamped by non-synchronous vibration or noise nor jumping between revolutions."""
        ok = np.broadcast_to(~self.in_doubt[:, None, None], self.vectors_um.shape)
        return ok.copy() if self.nonsync is None else ok & ~self.nonsync

    @property
    def amp_um_pp(self) -> np.ndarray:
        """Peak-to-peak amplitude 2A (µm), shape (n_steps, n_probes, n_orders)."""
        return 2.0 * np.abs(self.vectors_um)

    @property
    def phase_lag_deg(self) -> np.ndarray:
        """Phase lag φ in [0, 360) (degrees of the order's cycle); NaN without a keyphasor."""
        if not self.phase_referenced:
            return np.full(self.vectors_um.shape, np.nan)
        return np.mod(-np.degrees(np.angle(self.vectors_um)), 360.0)

    def peaks(self, order: int = 1) -> list[dict]:
        """Each probe's largest kX amplitude and its speed, where it is a resonance peak (the amplitude falls to
        1/√2 of it on both sides within the run; vectors that cannot be read, :meth:`readable`, left out)."""
        k = self.orders.index(order)
        amp = np.where(self.readable()[:, :, k], self.amp_um_pp[:, :, k], np.nan)
        out = []
        for p, (b, a) in enumerate(self.probes):
            if np.all(np.isnan(amp[:, p])):
                continue
            i = int(np.nanargmax(amp[:, p]))
            # a resonance peak: the response falls below half power (1/√2) on both sides within the run
            if not (np.nanmin(amp[:i + 1, p]) <= amp[i, p] / np.sqrt(2) and
                    np.nanmin(amp[i:, p]) <= amp[i, p] / np.sqrt(2)):
                continue
            out.append({"bearing": b, "angle_deg": a, "order": order, "speed_rpm": float(self.speed_rpm[i]),
                        "amp_um_pp": float(amp[i, p])})
        return out


def check_pulses(kp: np.ndarray, record_s: float) -> None:
    """Refuse a keyphasor pulse train that cannot be tracked: a missed or extra pulse (an interval off its
    neighbours'), pulses that stop before the record ends or start after it began (a dropout). Raises ValueError
    saying where."""
    kp = np.asarray(kp, dtype=float)
    if kp.size < 4:
        raise ValueError(f"keyphasor: {kp.size} pulse(s) in the record; a start-up needs one per revolution")
    if np.any(np.diff(kp) <= 0):
        raise ValueError("keyphasor_times_s must increase")
    per = np.diff(kp)
    if per.size >= 3:
        ratio = per[1:-1] / np.sqrt(per[:-2] * per[2:])
        bad = np.flatnonzero((ratio > PULSE_RATIO_MAX) | (ratio < 1.0 / PULSE_RATIO_MAX))
        if bad.size:
            i = int(bad[0]) + 1
            what = "a missed pulse or a dropout" if ratio[bad[0]] > 1 else "an extra pulse"
            raise ValueError(
                f"keyphasor drops out: the pulse interval at t = {kp[i]:.3f} s is {ratio[bad[0]]:.2f}× its "
                f"neighbours' ({what}; {bad.size} such interval(s)); the orders cannot be tracked through it. Cut the "
                "record there, repair the pulse train, or leave the keyphasor out to track the speed from the signal")
    if record_s - kp[-1] > PULSE_STOP_PERIODS * per[-1]:
        raise ValueError(f"keyphasor drops out: the last pulse is at t = {kp[-1]:.3f} s but the record runs to "
                         f"{record_s:.3f} s ({(record_s - kp[-1]) / per[-1]:.0f} revolutions without a pulse). Cut "
                         "the record at the last pulse or leave the keyphasor out")
    if kp[0] > PULSE_STOP_PERIODS * per[0]:
        raise ValueError(f"keyphasor: the first pulse is at t = {kp[0]:.3f} s, {kp[0] / per[0]:.0f} revolutions "
                         "into the record; cut the record at the first pulse or leave the keyphasor out")


def _kind_and_reversal(speed_rpm: np.ndarray, time_s: np.ndarray) -> str:
    """``run-up`` / ``coast-down`` / ``steady``; raises ValueError where the speed reverses."""
    n = speed_rpm.size
    w = min(9, n if n % 2 else n - 1)
    if w >= 3:
        pad = np.pad(speed_rpm, w // 2, mode="edge")
        s = np.median(np.lib.stride_tricks.sliding_window_view(pad, w), axis=1)
    else:
        s = speed_rpm
    rng = float(s.max() - s.min())
    if rng < 0.02 * float(s.mean()):
        return "steady"
    rising = s[-1] > s[0]
    back = (np.maximum.accumulate(s) - s) if rising else (s - np.minimum.accumulate(s))
    bad = np.flatnonzero(back > REVERSAL_FRACTION * rng)
    if bad.size:
        i = int(bad[0])
        turn = int(np.argmax(s[:i + 1])) if rising else int(np.argmin(s[:i + 1]))
        raise ValueError(
            f"the speed reverses at t = {time_s[turn]:.2f} s ({s[turn]:.0f} r/min): a "
            f"{'run-up' if rising else 'coast-down'} that turns back. Track each part alone (cut the record at "
            f"{time_s[turn]:.2f} s)")
    return "run-up" if rising else "coast-down"


def track_speed(rec: Recording, *, window_s: float = SPEED_WINDOW_S, hop_s: float = SPEED_HOP_S) -> SpeedTrack:
    """Running speed from the signal in windows of ``window_s`` (the steady estimator of
    :func:`rotordiag.features.extract_features` on each, with its doubts kept): a window whose estimate is
    ambiguous, fails, or jumps by more than :data:`SPEED_JUMP_MAX` against both neighbours is in doubt."""
    fs = rec.sample_rate_hz
    data = rec.xy_all_um()
    n = data.shape[1]
    wn = int(round(window_s * fs))
    hop = max(1, int(round(hop_s * fs)))
    if wn > n:
        raise ValueError(f"the record ({n / fs:.2f} s) is shorter than one speed window ({window_s:g} s)")
    starts = np.arange(0, n - wn + 1, hop)
    rpm = np.full(starts.size, np.nan)
    doubt = np.zeros(starts.size, dtype=bool)
    notes: list[str] = []
    for i, s0 in enumerate(starts):
        seg = data[:, s0:s0 + wn]
        seg = seg - seg.mean(axis=1, keepdims=True)
        try:
            f, warns = estimate_speed_hz(seg, fs, None if rec.speed_range_rpm is None else
                                         (rec.speed_range_rpm[0] / 60.0, rec.speed_range_rpm[1] / 60.0))
        except ValueError:
            doubt[i] = True
            continue
        rpm[i] = 60.0 * f
        if any(speed_in_doubt(w) for w in warns):
            doubt[i] = True
    ok = np.isfinite(rpm)
    for i in range(starts.size):
        nb = [j for j in (i - 1, i + 1) if 0 <= j < starts.size and ok[j]]
        if ok[i] and nb and all(abs(rpm[i] / rpm[j] - 1.0) > SPEED_JUMP_MAX for j in nb):
            doubt[i] = True
    n_doubt = int(doubt.sum())
    if n_doubt:
        t_bad = (starts[doubt] + wn / 2) / fs
        notes.append(f"speed in doubt in {n_doubt} of {starts.size} windows of {window_s:g} s "
                     f"(from t = {t_bad.min():.1f} s to {t_bad.max():.1f} s): left out of the plots")
    return SpeedTrack((starts + wn / 2) / fs, rpm, doubt, notes)


def _fit_steps(rec: Recording, theta: np.ndarray, bounds: np.ndarray, orders: tuple[int, ...]) -> tuple[
        np.ndarray, np.ndarray, np.ndarray]:
    """Least-squares fit per step (samples ``bounds[i]:bounds[i+1]``), every probe at once, of
    ``c0 + d0·u + Σ_k Re(C_k e^{jkθ})`` with u ∈ [−½, ½) the position within the step: the linear term takes up
    the gap's change across the step (the centreline rising), which would otherwise leak into the orders. The
    orders are held constant over the step: drift terms for them too would let the fit take non-synchronous
    lines near 1X (a whirl, a beat) for a changing 1X — measured on a simulated run-up of the paper's model, whose
    sub-synchronous whirl then doubled the 1X peak and made it ragged. The price is a leak of a fast-changing
    vector into the other orders through a sharp critical (0.3 % of the 1X through a ζ = 0.05 critical at
    40 r/min/s, tests/test_features_transient.py). The Gram matrices and right-hand sides are sums over each step
    (``np.add.reduceat``). Returns (C_k (n_steps, n_probes, n_orders) complex, c0 at mid-step (n_steps, n_probes),
    RMS of what the fit leaves (n_steps, n_probes))."""
    i0, i1 = int(bounds[0]), int(bounds[-1])
    th = theta[i0:i1]
    idx = (bounds[:-1] - i0).astype(np.intp)
    lengths = np.diff(bounds).astype(np.intp)
    n_steps = idx.size
    pos = np.arange(i1 - i0, dtype=float) - np.repeat(idx.astype(float), lengths)
    u = pos / np.repeat(lengths.astype(float), lengths) - 0.5
    cols = [np.ones_like(th), u]
    for k in orders:
        cols += [np.cos(k * th), np.sin(k * th)]
    m = len(cols)
    gram = np.empty((n_steps, m, m))
    for a in range(m):
        for b in range(a, m):
            g = np.add.reduceat(cols[a] * cols[b], idx)
            gram[:, a, b] = g
            gram[:, b, a] = g
    rhs = np.empty((n_steps, m, len(rec.channels)))
    sumsq = np.empty((n_steps, len(rec.channels)))
    for p, ch in enumerate(rec.channels):
        x = ch.data_um[i0:i1]
        for a in range(m):
            rhs[:, a, p] = np.add.reduceat(x * cols[a], idx)
        sumsq[:, p] = np.add.reduceat(x * x, idx)
    coef = np.linalg.solve(gram, rhs)  # (n_steps, m, n_probes)
    vec = np.empty((n_steps, len(rec.channels), len(orders)), dtype=complex)
    for j in range(len(orders)):
        vec[:, :, j] = coef[:, 2 + 2 * j] - 1j * coef[:, 3 + 2 * j]
    # least squares: residual sum of squares = Σx² − βᵀ(Dᵀx)
    rss = np.maximum(sumsq - np.einsum("sap,sap->sp", coef, rhs), 0.0)
    resid_rms = np.sqrt(rss / lengths[:, None])
    return vec, coef[:, 0], resid_rms


def _step_bounds(rev_idx: np.ndarray, n_revs: int, revs_per_step: int) -> np.ndarray:
    return rev_idx[::revs_per_step] if (n_revs % revs_per_step == 0) else \
        np.append(rev_idx[:-1:revs_per_step], rev_idx[-1])


def track_orders(rec: Recording, *, orders: tuple[int, ...] = (1, 2), revs_per_step: int = 1) -> OrderTrack:
    """1X/2X vectors of every probe, per revolution (``revs_per_step`` = 1) or per step of several revolutions.

    With ``rec.keyphasor_times_s`` the shaft angle comes from the pulses (checked by :func:`check_pulses`); without,
    from :func:`track_speed` (phases not referenced; steps where the speed is in doubt are flagged). Raises
    ValueError for a keyphasor that drops out, a speed that reverses, or a speed that cannot be tracked.
    """
    if not all(isinstance(k, (int, np.integer)) and 1 <= k <= 10 for k in orders) or not orders:
        raise ValueError(f"orders must be integers 1–10, got {orders!r}")
    revs_per_step = int(revs_per_step)
    if not 1 <= revs_per_step <= 1000:
        raise ValueError(f"revs_per_step must be in [1, 1000], got {revs_per_step!r}")
    fs = rec.sample_rate_hz
    n = rec.n_points
    t_end = (n - 1) / fs
    notes: list[str] = []
    if isinstance(rec.keyphasor_times_s, tuple):
        raise ValueError("a start-up needs one keyphasor for the whole record; this one has one per acquisition")
    if rec.keyphasor_times_s is not None:
        kp = np.asarray(rec.keyphasor_times_s, dtype=float)
        kp = kp[(kp >= 0) & (kp <= t_end)]
        check_pulses(kp, t_end)
        marks = kp
        source, referenced = "keyphasor", True
        doubt_at = None
    else:
        st = track_speed(rec)
        good = np.isfinite(st.speed_rpm) & ~st.in_doubt
        if good.sum() < max(2, 0.5 * st.speed_rpm.size):
            raise ValueError(f"the running speed cannot be tracked from the signal: in doubt in {int((~good).sum())} "
                             f"of {good.size} windows ({'; '.join(st.notes)}); give a keyphasor channel or pulse times")
        notes += st.notes
        notes.append("no keyphasor: speed tracked from the signal; phases are not referenced to a mark (no phase lag)")
        t = np.arange(n) / fs
        tg, fg = st.time_s[good], st.speed_rpm[good] / 60.0
        f_hz = np.interp(t, tg, fg)
        # the half window before the first and after the last window centre: the neighbouring slope carried on
        for sel, (i, j) in ((t < tg[0], (0, 1)), (t > tg[-1], (-2, -1))):
            slope = (fg[j] - fg[i]) / (tg[j] - tg[i])
            f_hz[sel] = fg[j if j == -1 else i] + slope * (t[sel] - tg[j if j == -1 else i])
        cyc = np.concatenate([[0.0], np.cumsum(0.5 * (f_hz[1:] + f_hz[:-1]) / fs)])
        k = np.arange(int(np.floor(cyc[-1])) + 1)
        marks = np.interp(k, cyc, t)
        source, referenced = "signal", False
        doubt_at = (st.time_s[good], 0.5 * SPEED_WINDOW_S)
    n_revs = marks.size - 1
    if n_revs < 2:
        raise ValueError(f"{n_revs} whole revolution(s) in the record; a start-up needs many")
    per = np.diff(marks)
    spr_min = fs * float(per.min())
    if spr_min < cfg.MIN_SAMPLES_PER_REV:
        raise ValueError(f"{spr_min:.1f} samples per revolution at the top speed ({60 / per.min():.0f} r/min); "
                         f"record at least {cfg.MIN_SAMPLES_PER_REV:g} per revolution (raise the sample rate)")
    rev_idx = np.ceil(marks * fs - 1e-9).astype(np.intp)
    rev_idx = np.clip(rev_idx, 0, n)
    t = np.arange(rev_idx[0], rev_idx[-1]) / fs
    theta = np.zeros(n)
    theta[rev_idx[0]:rev_idx[-1]] = 2 * np.pi * np.interp(t, marks, np.arange(marks.size, dtype=float))
    bounds = _step_bounds(rev_idx, n_revs, revs_per_step)
    vec, dc, resid = _fit_steps(rec, theta, bounds, tuple(int(k) for k in orders))
    # a revolution is one order wide: a line within an order of 1X (a whirl at 0.4–0.5X, a whip) leaks into the
    # fitted orders. Where what the fit leaves is larger than the orders it found, the orders are not read.
    sync_rms = np.sqrt(0.5 * np.sum(np.abs(vec) ** 2, axis=2))
    nonsync = np.repeat((resid > NONSYNC_MAX_RATIO * sync_rms)[:, :, None], len(orders), axis=2)
    # and a vector that jumps from one step to the next is no synchronous response (which turns by a few degrees
    # per revolution even through a critical) but a leak of a line beside the order, or the order in the noise
    if vec.shape[0] >= 3:
        jump = np.full(vec.shape, np.inf)
        jump[1:-1] = np.abs(vec[1:-1] - 0.5 * (vec[:-2] + vec[2:])) / np.maximum(np.abs(vec[1:-1]), 1e-12)
        jump[0], jump[-1] = jump[1], jump[-2]
        nonsync |= jump > VECTOR_JUMP_MAX
    # a few steps that pass among many that do not are chance, not a readable stretch
    for p_ in range(nonsync.shape[1]):
        for jo in range(nonsync.shape[2]):
            ok = np.concatenate([[False], ~nonsync[:, p_, jo], [False]])
            edges = np.flatnonzero(np.diff(ok.astype(np.int8)))
            for a, b in zip(edges[::2], edges[1::2]):
                if b - a < MIN_READABLE_RUN:
                    nonsync[a:b, p_, jo] = True
    # step speed from the marks the step spans
    mk = np.searchsorted(rev_idx, bounds)
    t0, t1 = marks[mk[:-1]], marks[mk[1:]]
    speed = 60.0 * (mk[1:] - mk[:-1]) / (t1 - t0)
    mid = 0.5 * (t0 + t1)
    in_doubt = np.zeros(speed.size, dtype=bool)
    if doubt_at is not None:
        good_t, half = doubt_at
        # a step is read only where a sound window covers it: not across a stretch of doubtful windows, nor past
        # the last sound one (the speed there is carried over, not measured)
        j = np.clip(np.searchsorted(good_t, mid), 1, good_t.size - 1)
        nearest = np.minimum(np.abs(mid - good_t[j - 1]), np.abs(mid - good_t[j]))
        in_doubt = nearest > half
    kind = _kind_and_reversal(speed, mid)
    for jo, order in enumerate(orders):
        bad = np.flatnonzero(nonsync[:, :, jo].sum(axis=1) * 2 > nonsync.shape[1])
        if bad.size:
            notes.append(f"{order}X not readable at most probes in {bad.size} of {speed.size} steps "
                         f"({speed[bad].min():.0f}–{speed[bad].max():.0f} r/min): non-synchronous vibration (a whirl "
                         "or whip? see the cascade) or noise swamps it, or it jumps between revolutions; left out of "
                         "the Bode, polar and peaks")
    if kind == "steady":
        notes.append("the speed changes by less than 2 %: a steady recording, not a start-up or coast-down")
    return OrderTrack(mid, speed, _probe_names(rec), tuple(int(k) for k in orders), vec, dc, referenced, source,
                      in_doubt, kind, bounds, notes, nonsync=nonsync, residual_rms_um=resid)


@dataclass(frozen=True)
class Waterfall:
    """Amplitude spectra of successive windows against speed (a cascade).

    Attributes
    ----------
    frequencies_hz : ndarray, shape (n_freq,)
        Negative frequencies (reverse whirl) first for a full spectrum.
    speed_rpm, time_s : ndarray, shape (n_slices,)
    amp_um_pp : ndarray, shape (n_slices, n_freq)
        Hann-window amplitude of each line, µm pk-pk (a pure sine reads its pk-pk at its bin).
    label : str
        What was analysed (``"b1@45"``, or ``"bearing 1 full spectrum"``).
    full : bool
    """

    frequencies_hz: np.ndarray
    speed_rpm: np.ndarray
    time_s: np.ndarray
    amp_um_pp: np.ndarray
    label: str
    full: bool


def _slices(track: OrderTrack, fs: float, n_points: int, window_s: float, max_slices: int) -> tuple[
        np.ndarray, np.ndarray, np.ndarray, int]:
    wn = int(2 ** np.round(np.log2(max(64.0, window_s * fs))))
    wn = min(wn, n_points)
    t_mid = track.time_s
    keep = np.flatnonzero(~track.in_doubt)
    if keep.size == 0:
        raise ValueError("no step of the run has a sound speed: no spectra")
    # evenly spread in time (a ramp: evenly in speed), each at the nearest sound step
    want = np.linspace(t_mid[keep[0]], t_mid[keep[-1]], min(max_slices, keep.size))
    pick = np.unique(keep[np.argmin(np.abs(t_mid[keep][None, :] - want[:, None]), axis=1)])
    starts = np.clip(np.round(t_mid[pick] * fs - wn / 2).astype(int), 0, n_points - wn)
    return starts, track.speed_rpm[pick], (starts + wn / 2) / fs, wn


def waterfall(rec: Recording, track: OrderTrack, probe: int = 0, *, window_s: float = 0.5,
              max_slices: int = 60) -> Waterfall:
    """Spectra of probe ``probe`` (index in ``rec.channels``) over ``max_slices`` windows of ``window_s`` spread
    over the run (mean removed per window, Hann window)."""
    fs = rec.sample_rate_hz
    starts, speed, times, wn = _slices(track, fs, rec.n_points, window_s, max_slices)
    x = rec.channels[probe].data_um
    seg = np.stack([x[s:s + wn] for s in starts])
    seg = seg - seg.mean(axis=1, keepdims=True)
    w = np.hanning(wn)
    spec = np.abs(np.fft.rfft(seg * w, axis=1)) * (4.0 / w.sum())  # pk-pk of a sine at its bin
    c = rec.channels[probe]
    return Waterfall(np.fft.rfftfreq(wn, 1.0 / fs), speed, times, spec, f"b{c.bearing}@{c.angle_deg:g}", False)


def full_spectrum(rec: Recording, track: OrderTrack, bearing: int, *, window_s: float = 0.5,
                  max_slices: int = 60) -> Waterfall:
    """Full-spectrum cascade of ``bearing``: the spectrum of x + jy. A forward circular orbit of radius r (0-pk)
    turning +x → +y at f reads 2r (its pk-pk) at +f, a reverse one at −f; an ellipse splits between the two."""
    fs = rec.sample_rate_hz
    starts, speed, times, wn = _slices(track, fs, rec.n_points, window_s, max_slices)
    xy = rec.xy_um(bearing)
    z = xy[0] + 1j * xy[1]
    seg = np.stack([z[s:s + wn] for s in starts])
    seg = seg - seg.mean(axis=1, keepdims=True)
    w = np.hanning(wn)
    spec = np.fft.fftshift(np.abs(np.fft.fft(seg * w, axis=1)), axes=1) * (2.0 / w.sum())
    f = np.fft.fftshift(np.fft.fftfreq(wn, 1.0 / fs))
    return Waterfall(f, speed, times, spec, f"bearing {bearing} full spectrum", True)


@dataclass(frozen=True)
class Centreline:
    """Mean journal position per step, µm: ``x_um``, ``y_um`` shape (n_steps, n_bearings); ``reference`` says from
    where (``"as recorded"``: the probes' own zero, for rotordiag's recordings and the simulator the bearing centre;
    ``"slow roll at the bottom"``: the slowest step's position put at (0, −c))."""

    bearings: tuple[int, ...]
    speed_rpm: np.ndarray
    x_um: np.ndarray
    y_um: np.ndarray
    clearance_um: dict[int, float]
    reference: str


def centreline(rec: Recording, track: OrderTrack, *, reference: str = "as recorded") -> Centreline:
    """The shaft-centreline path of every bearing from the tracked gaps (needs DC-coupled probes)."""
    if rec.dc_removed:
        raise ValueError("no shaft centreline: the recording's DC part is not a shaft position (AC-coupled probes "
                         "or a voltage record without gap_voltage_v)")
    if reference not in ("as recorded", "slow roll at the bottom"):
        raise ValueError(f"reference must be 'as recorded' or 'slow roll at the bottom', got {reference!r}")
    bearings = rec.bearings
    xs, ys = [], []
    for b in bearings:
        idx = [i for i, c in enumerate(rec.channels) if c.bearing == b]
        th1, th2 = np.deg2rad([rec.channels[i].angle_deg for i in idx])
        det = np.sin(th2 - th1)
        p1, p2 = track.dc_um[:, idx[0]], track.dc_um[:, idx[1]]
        xs.append((np.sin(th2) * p1 - np.sin(th1) * p2) / det)
        ys.append((-np.cos(th2) * p1 + np.cos(th1) * p2) / det)
    x, y = np.array(xs).T, np.array(ys).T
    clr = _clearances(rec)
    if reference == "slow roll at the bottom":
        if any(b not in clr for b in bearings):
            raise ValueError("'slow roll at the bottom' needs each bearing's clearance_um")
        i = int(np.argmin(track.speed_rpm))
        x = x - x[i]
        y = y - y[i] - np.array([clr[b] for b in bearings])
    return Centreline(bearings, track.speed_rpm.copy(), x, y, clr, reference)


def _clearances(rec: Recording) -> dict[int, float]:
    c = rec.clearance_um
    if c is None:
        return {}
    if isinstance(c, Mapping):
        return {int(b): float(v) for b, v in c.items() if v is not None}
    return {b: float(c) for b in rec.bearings}


@dataclass(frozen=True)
class Orbit:
    """One revolution of a bearing's orbit at ``speed_rpm``: raw ``x_um``/``y_um``, the 1X ellipse ``x1_um``/
    ``y1_um`` (64 points from the mark), and the keyphasor dot (the raw position at the mark, if referenced)."""

    bearing: int
    speed_rpm: float
    x_um: np.ndarray
    y_um: np.ndarray
    x1_um: np.ndarray
    y1_um: np.ndarray
    mark_um: tuple[float, float] | None


def orbits_at(rec: Recording, track: OrderTrack, speeds_rpm: list[float]) -> list[Orbit]:
    """Each bearing's orbit over the step nearest each requested speed (speeds outside the run are refused)."""
    lo, hi = float(track.speed_rpm.min()), float(track.speed_rpm.max())
    out = []
    k1 = track.orders.index(1) if 1 in track.orders else None
    for s in speeds_rpm:
        if not lo * 0.99 <= float(s) <= hi * 1.01:
            raise ValueError(f"orbit at {s:g} r/min: the run covers {lo:.0f}–{hi:.0f} r/min")
        i = int(np.argmin(np.abs(track.speed_rpm - float(s)) + np.where(track.in_doubt, np.inf, 0.0)))
        a, b_ = int(track.sample_bounds[i]), int(track.sample_bounds[i + 1])
        for b in rec.bearings:
            idx = [j for j, c in enumerate(rec.channels) if c.bearing == b]
            th1, th2 = np.deg2rad([rec.channels[j].angle_deg for j in idx])
            det = np.sin(th2 - th1)
            p1, p2 = rec.channels[idx[0]].data_um[a:b_], rec.channels[idx[1]].data_um[a:b_]
            xy = np.array([(np.sin(th2) * p1 - np.sin(th1) * p2) / det, (-np.cos(th2) * p1 + np.cos(th1) * p2) / det])
            if k1 is not None:
                c1, c2 = track.vectors_um[i, idx[0], k1], track.vectors_um[i, idx[1], k1]
                cx = (np.sin(th2) * c1 - np.sin(th1) * c2) / det
                cy = (-np.cos(th2) * c1 + np.cos(th1) * c2) / det
                ph = np.linspace(0, 2 * np.pi, 65)
                x1 = np.real(cx * np.exp(1j * ph)) + xy[0].mean()
                y1 = np.real(cy * np.exp(1j * ph)) + xy[1].mean()
            else:
                x1 = y1 = np.zeros(0)
            mark = (float(xy[0, 0]), float(xy[1, 0])) if track.phase_referenced else None
            out.append(Orbit(b, float(track.speed_rpm[i]), xy[0], xy[1], x1, y1, mark))
    return out
