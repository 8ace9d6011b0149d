"""``extract_features``: one recording → the fixed, named feature vector plus details."""
from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _config as cfg
from ._names import FEATURE_NAMES
from ._orbit import OrbitShape, orbit_shapes
from ._orders import fit_orders, forward_reverse, max_sync_order
from ._poincare import classify, poincare_points
from ._recording import Recording
from ._spectrum import band_power, noise_rms, residual_psd
from ._speed import refine_line_hz, shaft_angle

__all__ = ["BearingDetail", "FeatureResult", "extract_features"]

_NAME_INDEX = {n: i for i, n in enumerate(FEATURE_NAMES)}


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
        are DC-coupled and gap-referenced; not used as a feature).
    noise_rms_um : tuple of float
        Broadband noise estimate of x and y (median of the residual spectrum).
    poincare_um : ndarray, shape (n_revs, 2)
        x, y once per revolution (θ = 2πm).
    orbit12 : OrbitShape
        The filtered 1X + 2X orbit and its shape.
    features : dict
        This bearing's entries of the feature vector (``b{n}_…`` names).
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

    def phase_deg(self, direction: str, order: int) -> float:
        """Phase lag (deg, [0, 360)) of ``order`` in direction ``"x"`` or ``"y"``."""
        c = (self.x_coeffs_um if direction == "x" else self.y_coeffs_um)[order - 1]
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
    warnings : tuple of str
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

    def as_dict(self) -> dict[str, float]:
        """``{name: value}`` in schema order."""
        return dict(zip(self.names, (float(v) for v in self.values)))

    def __getitem__(self, name: str) -> float:
        try:
            return float(self.values[_NAME_INDEX[name]])
        except KeyError:
            raise KeyError(f"no feature named {name!r}; see features.FEATURE_NAMES") from None


def _ratio(num: float, den: float) -> float:
    return num / den if den > 0 else float("nan")


def _wrap_deg(d: float) -> float:
    d = d % 360.0
    return d - 360.0 if d > 180.0 else d


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

    def __enter__(self) -> "_BlasLimit":
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


def extract_features(recording: Recording) -> FeatureResult:
    """Features of one recording: order analysis, orbit shape, sub-harmonics, motion type.

    Parameters
    ----------
    recording : Recording
        x/y probe pairs of one or more bearings, sample rate, units, optional speed,
        keyphasor and clearance.

    Returns
    -------
    FeatureResult

    Raises
    ------
    ValueError
        With a message saying what to fix: fewer than ``MIN_REVS`` (8) revolutions, fewer than
        8 samples per revolution (3X too close to Nyquist), an unestimable speed, keyphasor
        pulses off the record. (Bad channels are refused when the ``Recording`` is built.)
    """
    if not isinstance(recording, Recording):
        raise ValueError(f"extract_features expects a features.Recording, got {type(recording).__name__}")
    with _blas_limit:
        return _extract(recording)


def _extract(recording: Recording) -> FeatureResult:
    rec = recording
    fs = rec.sample_rate_hz
    bearings = rec.bearings
    data = np.empty((2 * len(bearings), rec.n_points))  # x, y of each bearing
    for i, b in enumerate(bearings):
        rec.xy_um(b, out=data[2 * i:2 * i + 2])

    sa = shaft_angle(rec, data)
    warnings = list(sa.warnings)
    f1 = sa.speed_rpm / 60.0
    seg = data[:, sa.start:sa.stop]
    n_seg = seg.shape[1]
    k_max = max_sync_order(sa.min_samples_per_rev)
    uniform = None if sa.source == "keyphasor" else 2 * np.pi * f1 / fs
    coeffs, mean, resid = fit_orders(sa.theta_rad, seg, k_max, uniform_step_rad=uniform)

    if sa.source == "given":
        # check the given speed on the strongest order of the two strongest channels
        mag2 = np.abs(coeffs[:, :3]) ** 2
        power = mag2.sum(axis=0)
        h = int(np.argmax(power)) + 1
        if power[h - 1] > 0:
            top = np.argsort(-mag2[:, h - 1])[:2]
            f_sig = refine_line_hz(seg[top] - mean[top, None], fs, h * f1, iterations=1) / h
            if abs(f_sig / f1 - 1.0) > cfg.SPEED_MISMATCH_WARN:
                warnings.append(
                    f"speed_rpm {sa.speed_rpm:g} differs from the signal's {h}X line ({60 * f_sig / h * h:.2f} r/min, "
                    f"{100 * (f_sig / f1 - 1):+.2f} %); order amplitudes are underestimated and phases drift — "
                    "check the speed or give keyphasor_times_s")

    freqs, psd = residual_psd(resid, fs)
    orders_axis = freqs / f1
    bin_orders = fs / n_seg / f1                      # resolution (1/n_revs), not the padded bin spacing
    fft_bin_orders = float(orders_axis[1])
    noise = noise_rms(psd)
    # AC mean square about the fitted constant, without forming seg − mean
    ms = np.einsum("ij,ij->i", seg, seg) / n_seg - 2 * mean * seg.mean(axis=1) + mean ** 2
    res_ms = np.einsum("ij,ij->i", resid, resid) / n_seg
    ptp = np.ptp(seg, axis=1)
    sync0 = mean + coeffs.real.sum(axis=1)
    pts_all = poincare_points(sync0, resid, sa.start, fs, sa.rev_times_s)

    values = np.full(len(FEATURE_NAMES), np.nan)
    out: dict[str, float] = {"speed_rpm": sa.speed_rpm}
    details: dict[int, BearingDetail] = {}
    if sa.n_revs < cfg.MIN_REVS_SUBHARMONIC:
        warnings.append(f"only {sa.n_revs} revolutions: sub-harmonic band features have a resolution of "
                        f"{1 / sa.n_revs:.3f}X and are coarse (>= {cfg.MIN_REVS_SUBHARMONIC} revolutions recommended)")

    # everything per bearing that vectorises, computed for all bearings at once
    amp_pp = (2 * np.abs(coeffs[:, :3])).tolist()                       # (m, 3)
    phase = (np.degrees(-np.angle(coeffs[:, :3])) % 360.0).tolist()
    cx_all, cy_all = coeffs[0::2], coeffs[1::2]                           # (n_bearings, K)
    fw_all, rv_all = forward_reverse(cx_all, cy_all)
    afw_all, arv_all = np.abs(fw_all[:, :3]).tolist(), np.abs(rv_all[:, :3]).tolist()
    a1, r1 = np.abs(fw_all[:, 0]), np.abs(rv_all[:, 0])
    hints = np.where(a1 + r1 > 0, np.sign(a1 - r1), 1.0)
    orbits = orbit_shapes(cx_all[:, :2], cy_all[:, :2], hints)
    hw = max(cfg.CALLOUT_HALF_WIDTH_ORDERS, cfg.CALLOUT_MIN_HALF_WIDTH_BINS * bin_orders)
    bands = {"subsync": cfg.SUBSYNC_BAND, "whirl_band": cfg.WHIRL_BAND}
    for key, centre in cfg.CALLOUT_ORDERS.items():
        bands[key] = (centre - hw, centre + hw)
    top = int(np.searchsorted(orders_axis, max(hi for _, hi in bands.values()), side="right")) + 2
    pb_all = psd[0::2, :top] + psd[1::2, :top]                          # orbit (x + y) spectrum below 1X
    cum_all = np.concatenate([np.zeros((pb_all.shape[0], 1)), np.cumsum(pb_all, axis=1)], axis=1)
    sub_lo, sub_hi = np.searchsorted(orders_axis[:top], cfg.SUBSYNC_BAND, side="left")
    amp_list = ptp.tolist()
    spread = pts_all - pts_all.mean(axis=0)
    poincare_rms = np.sqrt(np.mean(spread[:, 0::2] ** 2 + spread[:, 1::2] ** 2, axis=0)).tolist()

    for i, b in enumerate(bearings):
        ix, iy = 2 * i, 2 * i + 1
        p = f"b{b}_"
        c = rec.clearance_for(b)
        f: dict[str, float] = {}
        for d, col in (("x", ix), ("y", iy)):
            amp = amp_pp[col]
            for k in cfg.REPORTED_ORDERS:
                f[f"{p}{d}_{k}x_amp_um_pp"] = amp[k - 1]
                f[f"{p}{d}_{k}x_amp_pp_per_c"] = amp[k - 1] / c
                f[f"{p}{d}_{k}x_phase_deg"] = phase[col][k - 1]
            f[f"{p}{d}_2x_1x_ratio"] = _ratio(amp[1], amp[0])
            f[f"{p}{d}_3x_1x_ratio"] = _ratio(amp[2], amp[0])
            f[f"{p}{d}_direct_um_pp"] = amp_list[col]
            f[f"{p}{d}_direct_pp_per_c"] = amp_list[col] / c
        afw, arv = afw_all[i], arv_all[i]
        for k in (1, 2):
            f[f"{p}{k}x_fwd_um_pp"] = 2 * afw[k - 1]
            f[f"{p}{k}x_fwd_pp_per_c"] = 2 * afw[k - 1] / c
            f[f"{p}{k}x_rev_um_pp"] = 2 * arv[k - 1]
            f[f"{p}{k}x_rev_pp_per_c"] = 2 * arv[k - 1] / c
            f[f"{p}{k}x_rev_fwd_ratio"] = _ratio(arv[k - 1], afw[k - 1])
        major = [2 * (a + r) for a, r in zip(afw, arv)]
        for k in cfg.REPORTED_ORDERS:
            f[f"{p}{k}x_major_um_pp"] = major[k - 1]
            f[f"{p}{k}x_major_pp_per_c"] = major[k - 1] / c
        f[f"{p}2x_1x_major_ratio"] = _ratio(major[1], major[0])
        f[f"{p}3x_1x_major_ratio"] = _ratio(major[2], major[0])
        s1 = afw[0] + arv[0]
        whirl_index = _ratio(afw[0] - arv[0], s1)
        f[f"{p}1x_ellipticity"] = abs(whirl_index)
        f[f"{p}1x_whirl_index"] = whirl_index
        f[f"{p}1x_whirl_dir"] = float(np.sign(afw[0] - arv[0])) if s1 > 0 else float("nan")
        orb = orbits[i]
        f[f"{p}orbit12_um_pp"] = orb.pp_um
        f[f"{p}orbit12_pp_per_c"] = orb.pp_um / c
        f[f"{p}orbit12_area_um2"] = orb.area_um2
        f[f"{p}orbit12_area_per_c2"] = orb.area_um2 / c ** 2
        # no 1X or 2X to speak of (below 1e-9 of the direct motion): no shape either
        degenerate = not orb.pp_um > 1e-9 * max(amp_list[ix], amp_list[iy])
        f[f"{p}orbit12_ellipticity"] = float("nan") if degenerate else orb.ellipticity
        f[f"{p}orbit12_turning_number"] = float("nan") if degenerate else float(orb.turning_number)
        f[f"{p}orbit12_loop"] = float("nan") if degenerate else float(orb.has_loop)
        f[f"{p}orbit12_concavity"] = float("nan") if degenerate else orb.concavity
        # sub-synchronous content of the orbit (x and y together)
        pb, cum = pb_all[i], cum_all[i]
        total_ms = float(ms[ix] + ms[iy])
        for key, (lo, hi) in bands.items():
            bms = band_power(cum, orders_axis[:top], lo, hi)
            rms = float(np.sqrt(bms))
            f[f"{p}{key}_rms_um"] = rms
            f[f"{p}{key}_rms_per_c"] = rms / c
            f[f"{p}{key}_frac"] = _ratio(bms, total_ms)
        peak_order = float("nan")
        if sub_hi - sub_lo >= 3:
            k = int(sub_lo + np.argmax(pb[sub_lo:sub_hi]))
            band = pb[sub_lo:sub_hi]
            med = float(np.partition(band, band.size // 2)[band.size // 2])
            distinct = pb[k] > cfg.SUBSYNC_PEAK_MIN_RATIO * med
            if distinct and pb[k] > cfg.SUBSYNC_PEAK_MIN_FRAC * total_ms and 0 < k < pb.size - 1:
                lp = np.log(np.maximum(pb[k - 1:k + 2], np.finfo(float).tiny))
                den = lp[0] - 2 * lp[1] + lp[2]
                delta = 0.5 * (lp[0] - lp[2]) / den if den < 0 else 0.0
                peak_order = float(orders_axis[k] + delta * fft_bin_orders)
        f[f"{p}subsync_peak_order"] = peak_order
        f[f"{p}nonsync_frac"] = _ratio(float(res_ms[ix] + res_ms[iy]), total_ms)
        pts = pts_all[:, ix:iy + 1]
        prms = poincare_rms[i]
        f[f"{p}poincare_rms_um"] = prms
        f[f"{p}poincare_rms_per_c"] = prms / c
        f[f"{p}poincare_disp"] = _ratio(prms, float(np.sqrt(total_ms)))
        out.update(f)

        cx, cy = cx_all[i], cy_all[i]
        chans = [ch for ch in rec.channels if ch.bearing == b]
        angles = np.deg2rad([ch.angle_deg for ch in chans])
        probe = np.vstack([np.cos(a) * cx + np.sin(a) * cy for a in angles])
        details[b] = BearingDetail(
            bearing=b, probe_angles_deg=(chans[0].angle_deg, chans[1].angle_deg), clearance_um=c,
            orders=tuple(range(1, k_max + 1)), x_coeffs_um=cx.copy(), y_coeffs_um=cy.copy(),
            probe_coeffs_um=probe, forward_um=fw_all[i].copy(), reverse_um=rv_all[i].copy(),
            mean_um=(float(mean[ix]), float(mean[iy])), noise_rms_um=(float(noise[ix]), float(noise[iy])),
            poincare_um=pts, orbit12=orb, features=f)

    for k in (1, 2):
        for bi, bj in cfg.PHASE_PAIRS:
            if bi in details and bj in details:
                for d in ("x", "y"):
                    ci = 2 * bearings.index(bi) + (d == "y")
                    cj = 2 * bearings.index(bj) + (d == "y")
                    out[f"dphase_{k}x_b{bi}_b{bj}_{d}_deg"] = _wrap_deg(phase[ci][k - 1] - phase[cj][k - 1])

    motion = None
    if sa.n_revs >= cfg.MIN_REVS_MOTION:
        orbit_size = float(np.max(ptp))
        motion, note = classify(pts_all, orbit_size, noise)
        if motion is None:
            warnings.append(note)
        else:
            out["motion_period"] = float(motion.period) if motion.kind == "period-n" else 0.0
            out["motion_quasi_periodic"] = float(motion.kind == "quasi-periodic")
            out["motion_chaotic"] = float(motion.kind == "chaotic")
    else:
        warnings.append(f"only {sa.n_revs} revolutions: motion type not determined "
                        f"(needs >= {cfg.MIN_REVS_MOTION})")

    for name, v in out.items():
        values[_NAME_INDEX[name]] = v
    return FeatureResult(
        names=FEATURE_NAMES, values=values, bearings=details, speed_rpm=float(sa.speed_rpm),
        speed_source=sa.source, phase_reference="keyphasor" if sa.source == "keyphasor" else "first sample",
        n_revs=sa.n_revs, motion_type=motion, warnings=tuple(warnings))
