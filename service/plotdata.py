"""Arrays the web page draws: orbits (raw and 1X / 2X filtered, once-per-revolution marks) and
spectra (half spectrum of each probe, full spectrum of each XY pair), per bearing.

The verdict itself comes from ``POST /diagnose``; this module only turns the same recording into
pictures. The filtered orbits are built from the features package's own order-analysis
coefficients (``BearingDetail.x_coeffs_um`` / ``y_coeffs_um``: the kX component of x is
``Re(C_k e^{jkθ})``) and its once-per-revolution points (``poincare_um``), so the page shows exactly
what the diagnosis analysed; only the display spectra (Hann-windowed FFT) are computed here.

Units: displacements in µm, frequencies in Hz; spectrum amplitudes in µm peak-to-peak (a line of
``A cos(2πft)`` reads ``2A`` when it falls on an FFT bin; off-bin lines read up to 15 % low, the
Hann window's scalloping loss).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from rotordiag.features import Recording

#: revolutions of the raw orbit shown (the last ones of the analysed segment)
ORBIT_REVS = 8
#: points per revolution of the filtered orbits
FILTERED_POINTS_PER_REV = 180
#: most raw-orbit points sent per axis (longer windows are strided)
MAX_RAW_POINTS = 4096
#: highest frequency of the spectra, in orders of running speed (capped at Nyquist)
SPECTRUM_MAX_ORDER = 4.5
#: most spectrum bins sent per trace (denser spectra are reduced by keeping each group's maximum)
MAX_SPECTRUM_BINS = 4096


def _finite_list(a: np.ndarray) -> list[float | None]:
    return [float(v) if np.isfinite(v) else None for v in np.asarray(a, dtype=float).ravel()]


def _rev_edges_s(recording: Any, bearing: int, n_revs: int, f1_hz: float, phase_reference: str) -> np.ndarray:
    """Times (s) of θ = 2πm for m = 0..n_revs at ``bearing``: the analysed revolutions' edges, as in the features
    package (the keyphasor pulses inside the record — the bearing's take's with one keyphasor per acquisition —,
    else θ = 0 at the first sample)."""
    if phase_reference == "keyphasor":
        t_end = (recording.n_points - 1) / recording.sample_rate_hz
        takes = recording.keyphasor_takes
        train = recording.keyphasor_times_s if takes is None else \
            next(kp for g, kp in zip(recording.acquisition_groups, takes) if bearing in g)
        kp = np.asarray(train, dtype=float)
        return kp[(kp >= 0) & (kp <= t_end)][: n_revs + 1]
    return np.arange(n_revs + 1) / f1_hz


def _reduce_max(freq: np.ndarray, amps: np.ndarray, max_bins: int) -> tuple[np.ndarray, np.ndarray]:
    """Keep at most ``max_bins`` bins: in each group of adjacent bins, the one where the largest of the
    traces peaks (so lines survive the reduction)."""
    n = freq.size
    if n <= max_bins:
        return freq, amps
    g = int(np.ceil(n / max_bins))
    m = n // g * g
    env = np.asarray(amps).reshape(-1, n)[:, :m].max(axis=0).reshape(m // g, g)
    idx = np.arange(m // g) * g + np.argmax(env, axis=1)
    return freq[idx], amps[..., idx]


def half_spectrum_um_pp(signals_um: np.ndarray, sample_rate_hz: float, f_max_hz: float
                        ) -> tuple[np.ndarray, np.ndarray]:
    """One-sided amplitude spectrum of real signals, µm peak-to-peak.

    Parameters
    ----------
    signals_um : ndarray, shape (n_signals, n_points)
    sample_rate_hz : float
    f_max_hz : float
        Highest frequency returned.

    Returns
    -------
    freq_hz : ndarray, shape (n_bins,)
    amp_um_pp : ndarray, shape (n_signals, n_bins)
        ``4|X_k| / Σw`` with a Hann window ``w`` (mean removed first); a line ``A cos(2πft)``
        on a bin reads ``2A``.
    """
    s = np.atleast_2d(np.asarray(signals_um, dtype=float))
    n = s.shape[1]
    w = np.hanning(n + 1)[:-1]            # periodic Hann: exact for lines on a bin
    spec = np.fft.rfft((s - s.mean(axis=1, keepdims=True)) * w, axis=1)
    freq = np.fft.rfftfreq(n, 1.0 / sample_rate_hz)
    keep = freq <= f_max_hz
    return freq[keep], 4.0 * np.abs(spec[:, keep]) / w.sum()


def full_spectrum_um_pp(x_um: np.ndarray, y_um: np.ndarray, sample_rate_hz: float, f_max_hz: float
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Full (two-sided) spectrum of ``x + jy``, µm peak-to-peak.

    Positive frequencies are forward whirl (x toward y, with the shaft), negative ones reverse whirl.
    A forward circle of radius r at f reads ``2r`` at +f; an XY pair's kX component
    ``x + jy = F e^{jkθ} + R e^{-jkθ}`` reads ``2|F|`` at +kX and ``2|R|`` at −kX (the features'
    ``b{n}_{k}x_fwd_um_pp`` / ``_rev_um_pp`` for on-bin lines).

    Returns
    -------
    freq_hz : ndarray, shape (n_bins,), increasing from −f_max to +f_max
    amp_um_pp : ndarray, shape (n_bins,)
    """
    z = np.asarray(x_um, dtype=float) + 1j * np.asarray(y_um, dtype=float)
    n = z.size
    w = np.hanning(n + 1)[:-1]            # periodic Hann: exact for lines on a bin
    spec = np.fft.fftshift(np.fft.fft((z - z.mean()) * w))
    freq = np.fft.fftshift(np.fft.fftfreq(n, 1.0 / sample_rate_hz))
    keep = np.abs(freq) <= f_max_hz
    return freq[keep], 2.0 * np.abs(spec[keep]) / w.sum()


def _filtered_orbit(cx: np.ndarray, cy: np.ndarray, orders: tuple[int, ...], n: int) -> dict[str, list]:
    """One revolution θ = 0..2π of Σ_k Re(C_k e^{jkθ}) for x and y (first point: θ = 0, the once-per-rev mark)."""
    theta = np.linspace(0.0, 2 * np.pi, n + 1)
    x = np.zeros_like(theta)
    y = np.zeros_like(theta)
    for k in orders:
        if k <= cx.size:
            e = np.exp(1j * k * theta)
            x += (cx[k - 1] * e).real
            y += (cy[k - 1] * e).real
    return {"x_um": _finite_list(x), "y_um": _finite_list(y)}


def plot_data(recording: Recording, feature_result: Any = None) -> dict[str, Any]:
    """Everything the page draws for one recording.

    Parameters
    ----------
    recording : features.Recording
    feature_result : features.FeatureResult, optional
        The recording's features as the verdict used them (``ModelStore.plot_features``: its speed may be
        one the model chose, ``models.checks.speed_choice``); ``extract_features(recording)`` when not given.

    Returns
    -------
    dict
        ``speed_rpm``, ``speed_source``, ``phase_reference``, ``sample_rate_hz``, ``n_revs``,
        ``whirl_band_orders``, ``warnings`` and ``bearings``: one entry per bearing with ``orbit``
        (``raw_x_um``/``raw_y_um`` mean-removed, ``raw_marks_um`` once per revolution, ``revs``,
        ``filtered`` → ``1x`` / ``2x`` / ``1x2x`` one revolution each) and ``half_spectrum``
        (``freq_hz``, ``amp_um_pp`` per probe, ``probe_angles_deg``) and ``full_spectrum``
        (``freq_hz`` negative to positive, ``amp_um_pp``).

    Raises
    ------
    ValueError
        From the features package, with a message for the user (too short, too slowly sampled...).
    """
    # Imported here: the server process loads the numeric stack only when the page asks for plots
    # (diagnoses run in the worker processes, service/pool.py).
    from rotordiag.features import (
        WHIRL_BAND,  # the features package's own oil-whirl band (orders), not a copy
        extract_features,
    )

    fr = extract_features(recording) if feature_result is None else feature_result
    fs = float(recording.sample_rate_hz)
    f1 = fr.speed_rpm / 60.0
    n = recording.n_points
    k = min(ORBIT_REVS, fr.n_revs)
    f_max = min(SPECTRUM_MAX_ORDER * f1, fs / 2)

    out_bearings = []
    for b, det in sorted(fr.bearings.items()):
        # the analysed segment (whole revolutions), as features.extract_features takes it
        edges = _rev_edges_s(recording, b, fr.n_revs, f1, fr.phase_reference)
        i0 = int(np.ceil(edges[0] * fs - 1e-9))
        i1 = min(n, int(np.ceil(edges[-1] * fs - 1e-9)))
        w0 = int(np.ceil(edges[-1 - k] * fs - 1e-9))
        stride = max(1, int(np.ceil((i1 - w0) / MAX_RAW_POINTS)))
        x, y = recording.xy_um(b)
        mx, my = det.mean_um
        marks = det.poincare_um[-k:] - np.array([mx, my])
        # each probe as mounted, p = x cos θ + y sin θ (µm whatever the input units)
        angles = np.deg2rad(det.probe_angles_deg)
        probes = np.vstack([np.cos(a) * x + np.sin(a) * y for a in angles])
        hf, ha = half_spectrum_um_pp(probes[:, i0:i1], fs, f_max)
        hf, ha = _reduce_max(hf, ha, MAX_SPECTRUM_BINS)
        ff, fa = full_spectrum_um_pp(x[i0:i1], y[i0:i1], fs, f_max)
        ff, fa = _reduce_max(ff, fa, MAX_SPECTRUM_BINS)
        cx, cy = det.x_coeffs_um, det.y_coeffs_um
        out_bearings.append({
            "bearing": int(b),
            "probe_angles_deg": [float(a) for a in det.probe_angles_deg],
            "mean_um": [float(mx), float(my)],
            "orbit": {
                "revs": k,
                "raw_x_um": _finite_list(x[w0:i1:stride] - mx),
                "raw_y_um": _finite_list(y[w0:i1:stride] - my),
                "raw_marks_um": [_finite_list(p) for p in marks],
                "filtered": {
                    "1x": _filtered_orbit(cx, cy, (1,), FILTERED_POINTS_PER_REV),
                    "2x": _filtered_orbit(cx, cy, (2,), FILTERED_POINTS_PER_REV),
                    "1x2x": _filtered_orbit(cx, cy, (1, 2), FILTERED_POINTS_PER_REV),
                },
            },
            "half_spectrum": {"freq_hz": _finite_list(hf), "amp_um_pp": [_finite_list(a) for a in ha]},
            "full_spectrum": {"freq_hz": _finite_list(ff), "amp_um_pp": _finite_list(fa)},
        })
    return {
        "speed_rpm": float(fr.speed_rpm),
        "speed_source": fr.speed_source,
        "phase_reference": fr.phase_reference,
        "sample_rate_hz": fs,
        "n_revs": int(fr.n_revs),
        "whirl_band_orders": [float(v) for v in WHIRL_BAND],
        "warnings": list(fr.warnings),
        "bearings": out_bearings,
    }


#: resolution of the start-up plots' PNGs on the page (the CLI writes 100 dpi; 80 keeps the answer ~1 MB)
TRANSIENT_PNG_DPI = 80


#: the page's names of the centreline references (``features.transient.centreline``'s ``reference``)
CENTRELINE_REFERENCES = {"recorded": "as recorded", "slow_roll": "slow roll at the bottom"}


def transient_plots(recording: Recording, units: str = "um", cascade_scale: str = "db",
                    plant: Any = None, centreline_reference: str = "recorded") -> dict[str, Any]:
    """A start-up or coast-down recording's plots as the page shows them: ``features.transient.track_orders``
    and ``features.plots.transient_figures`` (Bode, polar, cascade and full spectrum per bearing, centreline,
    orbits) rendered to PNG (base64), with the run's summary (``models.report.transient_summary``: kind, speed
    range and source, 1X/2X peaks, conventions, notes). ``units``: ``"um"`` or ``"mil"``; ``cascade_scale``: the
    cascades' trace height (``features.plots.CASCADE_SCALES``); ``centreline_reference``: ``"recorded"`` (the
    probes' own zero, or the gap voltage stated with a voltage record) or ``"slow_roll"`` (the slowest step's
    position put at the bottom of the clearance; needs the clearance). Raises ValueError
    (the features package's message) for a recording that cannot be tracked."""
    import base64
    import io

    import matplotlib.pyplot as plt

    from rotordiag.features.plots import transient_figures
    from rotordiag.features.transient import track_orders
    from rotordiag.models.report import transient_summary

    track = track_orders(recording)
    if centreline_reference not in CENTRELINE_REFERENCES:
        raise ValueError(f"centreline_reference must be one of {sorted(CENTRELINE_REFERENCES)}, got "
                         f"{centreline_reference!r}")
    figs = transient_figures(recording, track, units=units, cascade_scale=cascade_scale,
                             centreline_reference=CENTRELINE_REFERENCES[centreline_reference],
                             plant=plant)                       # with a plant model: its Campbell too
    try:
        figures = []
        for name, fig in figs.items():
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=TRANSIENT_PNG_DPI)
            figures.append({"name": name, "title": fig.axes[0].get_title() if fig.axes else name,
                            "png_base64": base64.b64encode(buf.getvalue()).decode("ascii")})
    finally:
        for fig in figs.values():
            plt.close(fig)
    return {**transient_summary(track), "units": units, "cascade_scale": cascade_scale,
            "centreline_reference": centreline_reference, "figures": figures}
