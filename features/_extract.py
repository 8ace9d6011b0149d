"""The one-pass feature extraction of a recording and its result types (``FeatureResult``, ``BearingDetail``).

The entry point, ``extract_features``, is in ``features._extraction``.
"""
from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from typing import Any

import numpy as np

from rotordiag.core.conventions import wrap_deg
from rotordiag.core.notes import Note

from . import _config as cfg
from ._acquisitions import format_acquisitions, split_pairs
from ._across import across_bearings
from ._lines import refine_line_hz
from ._names import FEATURE_NAMES
from ._orbit import OrbitShape, orbit_arrays
from ._orders import fit_orders, forward_reverse, max_sync_order
from ._poincare import classify, poincare_points
from ._recording import Recording
from ._spectrum import fast_length, hann_spectra, line_noise_amplitude, noise_rms, residual_psd
from ._speed import shaft_angle
from ._speed_lock import locked_speed_hz

__all__ = ["BearingDetail", "FeatureResult"]

_NAME_INDEX = {n: i for i, n in enumerate(FEATURE_NAMES)}
_SPEED_INDEX = _NAME_INDEX["speed_rpm"]


@cache
def _bearing_schema(bearing: int) -> tuple[tuple[str, ...], np.ndarray]:
    """The ``b{n}_…`` names of one bearing in schema order, and their indices in the vector. A train's bearing beyond
    the vector's four (5, 6, …) gets bearing 1's names with its own number and no index: its features are in its
    :class:`BearingDetail` only."""
    prefix = f"b{bearing}_"
    index = [i for i, n in enumerate(FEATURE_NAMES) if n.startswith(prefix)]
    if not index:
        names = tuple(prefix + FEATURE_NAMES[i][3:] for i in _bearing_schema(1)[1])
        return names, np.zeros(0, dtype=np.intp)
    arr = np.array(index, dtype=np.intp)
    arr.flags.writeable = False
    return tuple(FEATURE_NAMES[i] for i in index), arr


@dataclass(frozen=True)
class BearingDetail:
    """Everything computed for one bearing (µm; complex coefficients are zero-to-peak).

    Attributes
    ----------
    bearing : int
    probe_angles_deg : tuple of float
        The two probes' mounting angles, in channel order.
    clearance_um : float
        NaN when unknown.
    orders : tuple of int
        Orders fitted, 1..K.
    x_coeffs_um, y_coeffs_um : ndarray, complex, shape (K,)
        ``C_k`` of the horizontal / vertical displacement: the kX component is
        ``Re(C_k e^{jkθ}) = |C_k| cos(kθ − φ_k)``, ``φ_k = −arg C_k``.
    probe_coeffs_um : ndarray, complex, shape (2, K)
        The same for each probe as mounted (amplitude and phase per probe).
    forward_um, reverse_um : ndarray, complex, shape (K,)
        Forward / reverse components: ``x + jy = Σ F_k e^{jkθ} + R_k e^{-jkθ}``.
    mean_um : tuple of float
        Mean x, y over the analysed segment (the shaft centre position only if the probes
        are DC-coupled and gap-referenced).
    dc_removed : bool
        The recording carries no DC position (``Recording.dc_removed``, or every channel averaging
        to zero): ``mean_um`` is no shaft position and the centreline features are missing.
    noise_rms_um : tuple of float
        Broadband noise estimate of x and y (median of the residual spectrum).
    poincare_um : ndarray, shape (n_revs, 2)
        x, y once per revolution (θ = 2πm).
    orbit12 : OrbitShape
        The filtered 1X + 2X orbit and its shape.
    features : dict
        This bearing's entries of the feature vector (``b{n}_…`` names).
    line_noise_um : ndarray, shape (2, 3), optional
        Noise-equivalent zero-to-peak amplitude of the 1X–3X fit of x and y (µm, from the
        local noise floor; ``features._spectrum.line_noise_amplitude``).
    phase_valid : ndarray of bool, shape (2, 3), optional
        Whether the 1X–3X phase of x and y stands out of the noise (``PHASE_MIN_SNR``); where
        not, the phase features are NaN and :meth:`phase_deg` returns NaN.
    slow_roll_um_pp : tuple of (mapping or None), optional
        The slow-roll (runout) vectors subtracted from each probe's orders, in channel order
        (``ProbeChannel.slow_roll_um_pp``; an empty mapping: compensation asked for, no order above
        the noise at slow roll); None when no compensation was asked for at this bearing.
    """

    bearing: int
    probe_angles_deg: tuple[float, float]
    clearance_um: float
    orders: tuple[int, ...]
    x_coeffs_um: np.ndarray
    y_coeffs_um: np.ndarray
    probe_coeffs_um: np.ndarray
    forward_um: np.ndarray
    reverse_um: np.ndarray
    mean_um: tuple[float, float]
    noise_rms_um: tuple[float, float]
    poincare_um: np.ndarray
    orbit12: OrbitShape
    features: dict[str, float] = field(repr=False)
    line_noise_um: np.ndarray | None = field(default=None, repr=False)
    phase_valid: np.ndarray | None = field(default=None, repr=False)
    slow_roll_um_pp: tuple[Any, Any] | None = field(default=None, repr=False)
    dc_removed: bool = False

    def phase_deg(self, direction: str, order: int) -> float:
        """Phase lag (deg, [0, 360)) of ``order`` in direction ``"x"`` or ``"y"``."""
        c = (self.x_coeffs_um if direction == "x" else self.y_coeffs_um)[order - 1]
        if self.phase_valid is not None and order <= self.phase_valid.shape[1] \
                and not self.phase_valid[0 if direction == "x" else 1, order - 1]:
            return float("nan")
        return float(np.degrees(-np.angle(c)) % 360.0)


@dataclass(frozen=True)
class FeatureResult:
    """Result of :func:`extract_features`.

    Attributes
    ----------
    names : tuple of str
        The fixed feature names (``features.FEATURE_NAMES``), same for every recording.
    values : ndarray, shape (n_features,), float64
        NaN for features of absent bearings, unknown clearance, undefined ratios.
    bearings : dict of int → BearingDetail
        Bearings present.
    speed_rpm : float
    speed_source : str
        ``"keyphasor"``, ``"given"`` or ``"estimated"``.
    phase_reference : str
        ``"keyphasor"`` (phase lag from the pulse) or ``"first sample"``.
    n_revs : int
        Whole revolutions analysed.
    motion_type : simulator.analysis.MotionType or None
        None when the record is too short or the classifier is unavailable.
    warnings : tuple of rotordiag.core.notes.Note
    sanity : tuple of features.SanityFinding
        Physics sanity findings (``features._sanity.check_recording``); empty when all pass.
    """

    names: tuple[str, ...]
    values: np.ndarray
    bearings: dict[int, BearingDetail]
    speed_rpm: float
    speed_source: str
    phase_reference: str
    n_revs: int
    motion_type: Any
    warnings: tuple[str, ...]
    sanity: tuple = ()
    #: groups of bearings sampled together (``Recording.acquisitions``); ``()``: every channel sampled together
    acquisitions: tuple[tuple[int, ...], ...] = ()

    def __post_init__(self) -> None:
        foreign = [w for w in self.warnings if not isinstance(w, Note)]
        if foreign:                 # a programming error: every warning is a catalogue note (rotordiag.core.notes)
            raise TypeError(f"FeatureResult.warnings: {foreign[:2]!r} are not Notes of the warnings catalogue "
                            "(rotordiag.core.notes)")

    def as_dict(self) -> dict[str, float]:
        """``{name: value}`` in schema order."""
        return dict(zip(self.names, (float(v) for v in self.values)))

    def __getitem__(self, name: str) -> float:
        try:
            return float(self.values[_NAME_INDEX[name]])
        except KeyError:
            raise KeyError(f"no feature named {name!r}; see features.FEATURE_NAMES") from None


def _ratios(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """``num / den`` where ``den > 0``, else NaN (element-wise; call under ``np.errstate``)."""
    return np.where(den > 0, num / den, np.nan)


def _subsync_peak_orders(pb: np.ndarray, lo: int, hi: int, total_ms: np.ndarray, orders: np.ndarray,
                         bin_orders: float) -> np.ndarray:
    """Order of the largest sub-synchronous line of each orbit spectrum row (NaN when not distinct)."""
    out = np.full(pb.shape[0], np.nan)
    if hi - lo < 3:
        return out
    band = pb[:, lo:hi]
    peak = lo + np.argmax(band, axis=1)
    mid = band.shape[1] // 2
    med = np.partition(band, mid, axis=1)[:, mid]
    tiny = np.finfo(float).tiny
    for i in range(pb.shape[0]):
        k = int(peak[i])
        row = pb[i]
        distinct = row[k] > cfg.SUBSYNC_PEAK_MIN_RATIO * med[i]
        if distinct and row[k] > cfg.SUBSYNC_PEAK_MIN_FRAC * total_ms[i] and 0 < k < row.size - 1:
            lp = np.log(np.maximum(row[k - 1:k + 2], tiny))
            den = lp[0] - 2 * lp[1] + lp[2]
            delta = 0.5 * (lp[0] - lp[2]) / den if den < 0 else 0.0
            out[i] = float(orders[k] + delta * bin_orders)
    return out


def _means_removed(data: np.ndarray) -> bool:
    """Whether every row of ``data`` (x/y of each bearing, µm) averages to zero within ``DC_REMOVED_MAX_REL`` of the
    largest peak-to-peak: its DC part was removed before it reached us (a real journal never sits at the exact
    centre of every bearing)."""
    scale = float(np.max(np.ptp(data, axis=1)))
    return bool(scale > 0 and np.all(np.abs(data.mean(axis=1)) <= cfg.DC_REMOVED_MAX_REL * scale))


def _centreline_per_c(mean_x_um: np.ndarray, mean_y_um: np.ndarray, clearance_um: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Static journal position per bearing in clearances: x, y and eccentricity ratio.

    NaN when the clearance is unknown or the mean reading lies more than
    ``CENTRELINE_MAX_ECC`` clearances from the probes' zero (then the DC part is a raw
    probe gap, not a position inside the bearing).
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        ex, ey = mean_x_um / clearance_um, mean_y_um / clearance_um
        ecc = np.hypot(ex, ey)
    bad = ~(ecc <= cfg.CENTRELINE_MAX_ECC)
    return np.where(bad, np.nan, ex), np.where(bad, np.nan, ey), np.where(bad, np.nan, ecc)


def _subtract_slow_roll(rec: Recording, bearings: tuple[int, ...], coeffs: np.ndarray) -> None:
    """Subtract the probes' slow-roll (runout) vectors from the fitted x/y orders, in place.

    A probe reads ``p = x cos θ + y sin θ``; its slow-roll coefficient is mapped to x and y
    with the same inverse projection as the waveforms (``Recording.xy_um``), per order.
    """
    for i, b in enumerate(bearings):
        pair = [c for c in rec.channels if c.bearing == b]
        if not (pair[0].slow_roll_um_pp or pair[1].slow_roll_um_pp):
            continue
        th1, th2 = np.deg2rad(pair[0].angle_deg), np.deg2rad(pair[1].angle_deg)
        det = np.sin(th2 - th1)
        s1, s2 = pair[0].slow_roll_coeffs_um(), pair[1].slow_roll_coeffs_um()
        for k in (1, 2):
            if k > coeffs.shape[1]:
                continue
            p1, p2 = s1.get(k, 0j), s2.get(k, 0j)
            coeffs[2 * i, k - 1] -= (np.sin(th2) * p1 - np.sin(th1) * p2) / det
            coeffs[2 * i + 1, k - 1] -= (-np.cos(th2) * p1 + np.cos(th1) * p2) / det


class _BlasLimit:
    """Limit BLAS threads to ``cfg.BLAS_THREADS`` while any extraction runs (thread-safe).

    The BLAS thread count is process-wide, so concurrent extractions share one limit: the first
    to enter sets it, the last to leave restores the caller's setting.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._active = 0
        self._controller: Any = None
        self._restore: Any = None

    def __enter__(self) -> _BlasLimit:
        with self._lock:
            if self._active == 0 and cfg.BLAS_THREADS is not None:
                if self._controller is None:
                    try:
                        from threadpoolctl import ThreadpoolController
                        self._controller = ThreadpoolController()
                    except Exception:  # pragma: no cover - threadpoolctl ships with scikit-learn
                        self._controller = False
                if self._controller:
                    self._restore = self._controller.limit(limits=cfg.BLAS_THREADS, user_api="blas")
            self._active += 1
        return self

    def __exit__(self, *exc: object) -> None:
        with self._lock:
            self._active -= 1
            if self._active == 0 and self._restore is not None:
                self._restore.restore_original_limits()
                self._restore = None


_blas_limit = _BlasLimit()


def _given_speed_mismatch(seg: np.ndarray, mean: np.ndarray, fs: float, f1: float,
                          coeffs: np.ndarray) -> tuple[int, float] | None:
    """The order and the running speed (Hz) the signal's synchronous lines read when they disagree with a given
    speed ``f1`` by more than ``SPEED_MISMATCH_WARN``, else None.

    The strongest of the 1X–3X orders is refined (``refine_line_hz``, on the two channels that carry it most)
    and read as a running speed. A reading off the given speed counts when the other synchronous lines confirm it
    (``_speed_lock.locked_speed_hz`` at that reading, within ``SPEED_CHECK_LOCK_REL``: a sample rate or a speed
    that is off moves every synchronous line alike), or, with no second line to confirm it, when no
    sub-synchronous line outgrows the 1X (:func:`_whirl_dominates`): a whirl's 2nd harmonic in the 1X's main lobe
    pulls the 1X reading alone (without that test the check warned on whirl records at the right speed;
    docs/features.md, "Measurements behind the speed estimate's thresholds")."""
    mag2 = np.abs(coeffs[:, :3]) ** 2
    power = mag2.sum(axis=0)
    h = int(np.argmax(power)) + 1
    if not power[h - 1] > 0:
        return None
    strongest = np.argsort(-mag2[:, h - 1])[:2]
    f_sig = refine_line_hz(seg[strongest] - mean[strongest, None], fs, h * f1, iterations=1) / h
    if not abs(f_sig / f1 - 1.0) > cfg.SPEED_MISMATCH_WARN:
        return None
    f_lock = locked_speed_hz(seg, fs, f_sig, max_rel=cfg.SPEED_CHECK_LOCK_REL)
    if f_lock is not None:
        return h, f_lock
    return None if _whirl_dominates(seg, fs, f_sig) else (h, f_sig)


def _whirl_dominates(seg: np.ndarray, fs: float, f1: float) -> bool:
    """Whether the largest line between 0.2 and 0.8 × ``f1`` (summed Hann power of the channels) stands above the
    largest one within two bins of ``f1``."""
    _, _, power = hann_spectra(seg)
    df = fs / fast_length(seg.shape[1])
    k1 = int(round(f1 / df))
    lo, hi = max(int(0.2 * f1 / df), 1), int(0.8 * f1 / df)
    if hi <= lo or k1 + 3 > power.size:
        return False
    return bool(power[lo:hi + 1].max() > power[max(k1 - 2, 0):k1 + 3].max())


def _extract(recording: Recording, estimate: tuple[float, list[str]] | None = None) -> FeatureResult:
    """The features of a recording sampled together (or whose takes share no phase reference), before the
    sanity checks."""
    rec = recording
    fs = rec.sample_rate_hz
    bearings = rec.bearings
    data = rec.xy_all_um()                          # x, y of each bearing

    sa = shaft_angle(rec, data, estimate)
    if sa.source != "keyphasor" and any(c.slow_roll_um_pp for c in rec.channels):
        # the slow-roll vectors are keyphasor-referenced; orders referenced to the first sample cannot take them
        raise ValueError(f"slow-roll compensation needs the keyphasor's phase reference, and {sa.warnings[0]}. Fix the "
                         "keyphasor signal, or send the recording without the slow-roll vectors / recording")
    warnings = list(sa.warnings)
    dc_removed = rec.dc_removed or _means_removed(data)
    if dc_removed:
        warnings.append(Note("no_dc_position", why=(
            "dc_removed" if rec.dc_removed else "every channel averages to zero: the means were removed, or the "
            "acquisition is AC-coupled")))
    f1 = sa.speed_rpm / 60.0
    seg = data[:, sa.start:sa.stop]
    n_seg = seg.shape[1]
    k_max = max_sync_order(sa.min_samples_per_rev)
    uniform = None if sa.source == "keyphasor" else 2 * np.pi * f1 / fs
    coeffs, mean, resid = fit_orders(sa.theta_rad, seg, k_max, uniform_step_rad=uniform)

    _subtract_slow_roll(rec, bearings, coeffs)

    freqs, psd = residual_psd(resid, fs)
    orders_axis = freqs / f1
    bin_orders = fs / n_seg / f1                      # resolution (1/n_revs), not the padded bin spacing
    noise = noise_rms(psd)
    # the phase of an order is missing (NaN), not noise, when the order does not stand out of the
    # local noise floor (or is numerically nil): cfg.PHASE_MIN_SNR, cfg.PHASE_MIN_REL_AMPLITUDE
    n_rep = len(cfg.REPORTED_ORDERS)
    line_noise = line_noise_amplitude(psd, orders_axis, n_seg, cfg.REPORTED_ORDERS, cfg.PHASE_NOISE_BAND_ORDERS)
    amp0 = np.abs(coeffs[:, :n_rep])
    rel_floor = cfg.PHASE_MIN_REL_AMPLITUDE * float(np.max(np.abs(coeffs))) if coeffs.size else 0.0
    with np.errstate(invalid="ignore"):
        phase_ok = (amp0 > rel_floor) & ~(amp0 < cfg.PHASE_MIN_SNR * line_noise)
    # AC mean square about the fitted constant, without forming seg − mean
    ms = np.einsum("ij,ij->i", seg, seg) / n_seg - 2 * mean * seg.mean(axis=1) + mean ** 2
    res_ms = np.einsum("ij,ij->i", resid, resid) / n_seg
    if sa.source == "given":
        mismatch = _given_speed_mismatch(seg, mean, fs, f1, coeffs)
        if mismatch is not None:
            h, f_sig = mismatch
            warnings.append(Note("speed_off_line", given_rpm=sa.speed_rpm, order=h, line_rpm=60 * f_sig,
                                 off_pct=100 * (f_sig / f1 - 1)))
    ptp = np.ptp(seg, axis=1)
    sync0 = mean + coeffs.real.sum(axis=1)
    pts_all = poincare_points(sync0, resid, sa.start, fs, sa.rev_times_s)

    values = np.full(len(FEATURE_NAMES), np.nan)
    values[_SPEED_INDEX] = sa.speed_rpm
    if sa.n_revs < cfg.MIN_REVS_SUBHARMONIC:
        warnings.append(Note("few_revolutions_subharmonic", n_revs=sa.n_revs, resolution_x=1 / sa.n_revs,
                             min_revs=cfg.MIN_REVS_SUBHARMONIC))

    # every per-bearing feature as a column over the bearings present (schema order), then one
    # scatter into ``values``: the arithmetic is element-wise, so each value is the same float as
    # computing it bearing by bearing
    c = np.array([rec.clearance_for(b) for b in bearings])
    amp_pp = 2 * np.abs(coeffs[:, :3])                                   # (m, 3)
    phase = np.where(phase_ok, np.degrees(-np.angle(coeffs[:, :3])) % 360.0, np.nan)
    cx_all, cy_all = coeffs[0::2], coeffs[1::2]                           # (n_bearings, K)
    fw_all, rv_all = forward_reverse(cx_all, cy_all)
    afw, arv = np.abs(fw_all[:, :3]), np.abs(rv_all[:, :3])
    a1, r1 = afw[:, 0], arv[:, 0]
    hints = np.where(a1 + r1 > 0, np.sign(a1 - r1), 1.0)
    orb = orbit_arrays(cx_all[:, :2], cy_all[:, :2], hints)
    hw = max(cfg.CALLOUT_HALF_WIDTH_ORDERS, cfg.CALLOUT_MIN_HALF_WIDTH_BINS * bin_orders)
    bands = {"subsync": cfg.SUBSYNC_BAND, "whirl_band": cfg.WHIRL_BAND}
    for key, centre in cfg.CALLOUT_ORDERS.items():
        bands[key] = (centre - hw, centre + hw)
    top = int(np.searchsorted(orders_axis, max(hi for _, hi in bands.values()), side="right")) + 2
    pb_all = psd[0::2, :top] + psd[1::2, :top]                          # orbit (x + y) spectrum below 1X
    cum_all = np.concatenate([np.zeros((pb_all.shape[0], 1)), np.cumsum(pb_all, axis=1)], axis=1)
    sub_lo, sub_hi = np.searchsorted(orders_axis[:top], cfg.SUBSYNC_BAND, side="left")
    spread = pts_all - pts_all.mean(axis=0)
    poincare_rms = np.sqrt(np.mean(spread[:, 0::2] ** 2 + spread[:, 1::2] ** 2, axis=0))
    total_ms = ms[0::2] + ms[1::2]
    nan = np.nan

    cols: list[np.ndarray] = []
    with np.errstate(divide="ignore", invalid="ignore"):
        for d in (0, 1):                                                # x, y
            amp, ph, direct = amp_pp[d::2], phase[d::2], ptp[d::2]
            for k in range(3):
                cols += [amp[:, k], amp[:, k] / c, ph[:, k]]
            cols += [_ratios(amp[:, 1], amp[:, 0]), _ratios(amp[:, 2], amp[:, 0]), direct, direct / c]
        for k in range(2):
            fw2, rv2 = 2 * afw[:, k], 2 * arv[:, k]
            cols += [fw2, fw2 / c, rv2, rv2 / c, _ratios(arv[:, k], afw[:, k])]
        major = 2 * (afw + arv)
        for k in range(3):
            cols += [major[:, k], major[:, k] / c]
        cols += [_ratios(major[:, 1], major[:, 0]), _ratios(major[:, 2], major[:, 0])]
        s1 = a1 + r1
        whirl_index = _ratios(a1 - r1, s1)
        cols += [np.abs(whirl_index), whirl_index, np.where(s1 > 0, np.sign(a1 - r1), nan)]
        pp = orb.pp
        # no 1X or 2X to speak of (below 1e-9 of the direct motion): no shape either
        degenerate = ~(pp > 1e-9 * np.maximum(ptp[0::2], ptp[1::2]))
        cols += [pp, pp / c, orb.area, orb.area / c ** 2,
                 np.where(degenerate, nan, orb.ellipticity),
                 np.where(degenerate, nan, orb.turning.astype(float)),
                 np.where(degenerate, nan, (np.abs(orb.turning) != 1).astype(float)),
                 np.where(degenerate, nan, orb.concavity)]
        # sub-synchronous content of the orbit (x and y together)
        for lo, hi in bands.values():
            i0, i1 = np.searchsorted(orders_axis[:top], [lo, hi], side="left")
            bms = cum_all[:, i1] - cum_all[:, i0]
            rms = np.sqrt(bms)
            cols += [rms, rms / c, _ratios(bms, total_ms)]
        cols.append(_subsync_peak_orders(pb_all, sub_lo, sub_hi, total_ms, orders_axis, float(orders_axis[1])))
        cols.append(_ratios(res_ms[0::2] + res_ms[1::2], total_ms))
        cols += [poincare_rms, poincare_rms / c, _ratios(poincare_rms, np.sqrt(total_ms))]
        centreline = _centreline_per_c(mean[0::2], mean[1::2], c)
        cols += [np.full_like(v, nan) for v in centreline] if dc_removed else list(centreline)
    table = np.column_stack(cols)                                      # (n_bearings, features per bearing)

    details: dict[int, BearingDetail] = {}
    orders = tuple(range(1, k_max + 1))
    for i, b in enumerate(bearings):
        ix, iy = 2 * i, 2 * i + 1
        names, index = _bearing_schema(b)
        row = table[i]
        if index.size:
            values[index] = row
        cx, cy = cx_all[i], cy_all[i]
        chans = [ch for ch in rec.channels if ch.bearing == b]
        angles = np.deg2rad([chans[0].angle_deg, chans[1].angle_deg])
        probe = np.cos(angles)[:, None] * cx + np.sin(angles)[:, None] * cy
        details[b] = BearingDetail(
            bearing=b, probe_angles_deg=(chans[0].angle_deg, chans[1].angle_deg), clearance_um=float(c[i]),
            orders=orders, x_coeffs_um=cx.copy(), y_coeffs_um=cy.copy(),
            probe_coeffs_um=probe, forward_um=fw_all[i].copy(), reverse_um=rv_all[i].copy(),
            mean_um=(float(mean[ix]), float(mean[iy])), dc_removed=dc_removed, noise_rms_um=(float(noise[ix]), float(noise[iy])),
            poincare_um=pts_all[:, ix:iy + 1], orbit12=orb.shape(i), features=dict(zip(names, row.tolist())),
            line_noise_um=line_noise[ix:iy + 1].copy(), phase_valid=phase_ok[ix:iy + 1].copy(),
            slow_roll_um_pp=None if chans[0].slow_roll_um_pp is None and chans[1].slow_roll_um_pp is None
            else (chans[0].slow_roll_um_pp, chans[1].slow_roll_um_pp))

    warnings += phase_differences(values, details, rec.acquisition_groups)
    across_bearings(values)

    motion = None
    if sa.n_revs >= cfg.MIN_REVS_MOTION:
        orbit_size = float(np.max(ptp))
        motion, note = classify(pts_all, orbit_size, noise)
        if motion is None and note is not None:
            warnings.append(note)
        else:
            values[_NAME_INDEX["motion_period"]] = float(motion.period) if motion.kind == "period-n" else 0.0
            values[_NAME_INDEX["motion_quasi_periodic"]] = float(motion.kind == "quasi-periodic")
            values[_NAME_INDEX["motion_chaotic"]] = float(motion.kind == "chaotic")
    else:
        warnings.append(Note("few_revolutions_motion", n_revs=sa.n_revs, min_revs=cfg.MIN_REVS_MOTION))

    result = FeatureResult(
        names=FEATURE_NAMES, values=values, bearings=details, speed_rpm=float(sa.speed_rpm),
        speed_source=sa.source, phase_reference="keyphasor" if sa.source == "keyphasor" else "first sample",
        n_revs=sa.n_revs, motion_type=motion, warnings=tuple(warnings), acquisitions=rec.acquisition_groups)
    return result


def phase_differences(values: np.ndarray, details: dict[int, BearingDetail],
                      acquisitions: Sequence[Sequence[int]],
                      why: str = "the takes' start times are not related; record the bearings either side of the "
                                 "coupling together for the phase across it, or give a keyphasor per acquisition"
                      ) -> list[str]:
    """Write the ``dphase_*`` features of the bearings in ``details`` into ``values`` (in place): each order's
    phase lag of one bearing minus the other's, missing where either phase is in the noise
    (:meth:`BearingDetail.phase_deg`) or the two bearings lie in different ``acquisitions`` (groups whose
    phases are not related). Returns the warning that names those pairs, with ``why`` (none when there are
    none)."""
    split = split_pairs(acquisitions, cfg.PHASE_PAIRS)
    for k in (1, 2):
        for bi, bj in cfg.PHASE_PAIRS:
            if bi in details and bj in details and (bi, bj) not in split:
                for axis in ("x", "y"):
                    values[_NAME_INDEX[f"dphase_{k}x_b{bi}_b{bj}_{axis}_deg"]] = float(wrap_deg(
                        details[bi].phase_deg(axis, k) - details[bj].phase_deg(axis, k)))
    if not split:
        return []
    return [Note("separate_acquisitions_unreferenced", groups=format_acquisitions(acquisitions),
                 pairs=", ".join(f"bearings {i} and {j}" for i, j in split), why=why)]
