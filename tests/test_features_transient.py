"""Order tracking of start-ups and coast-downs (features.transient), their plots (features.plots) and the CLI doors."""
from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording
from rotordiag.features import transient as T

FS = 2560.0
LAYOUT = [(b, a) for b in (1, 2) for a in (45.0, 135.0)]


def _ramp(rpm0: float, rpm1: float, dur_s: float, fs: float = FS):
    """Exact shaft angle of a linear ramp, its revolution times, and the speed at each sample."""
    t = np.arange(int(dur_s * fs)) / fs
    a = (rpm1 - rpm0) / dur_s / 60.0            # rev/s²
    revs = rpm0 / 60.0 * t + 0.5 * a * t * t
    k = np.arange(int(np.floor(revs[-1])) + 1)
    f0 = rpm0 / 60.0
    kp = (2 * k / (f0 + np.sqrt(f0 * f0 + 2 * a * k))) if a else k / f0
    return t, 2 * np.pi * revs, kp, 60.0 * (f0 + a * t)


def _amp1(rpm: np.ndarray) -> np.ndarray:
    """A 1X amplitude (0-pk, µm) with a resonance at 1500 r/min, ζ = 0.05."""
    r = rpm / 1500.0
    return 10.0 * r * r / np.sqrt((1 - r * r) ** 2 + (0.1 * r) ** 2)


def _synthetic(rpm0=900.0, rpm1=2100.0, dur_s=30.0, noise_um=0.0, seed=0, keyphasor=True, ellipticity=0.5):
    """Probe signals with known 1X (resonant, its phase turning through 90° at 1500 r/min), 2X (constant) and gaps:
    each probe reads the projection of a forward elliptical 1X orbit x = a cos(θ − lag), y = e·a sin(θ − lag), a 2X
    of its own, and the gap (DC) of a centreline rising with speed. Returns (recording, {probe: true complex 1X at
    a speed → C1(rpm), 2X}, speed at the samples)."""
    t, th, kp, rpm = _ramp(rpm0, rpm1, dur_s)
    r = rpm / 1500.0
    lag1 = np.arctan2(0.1 * r, 1 - r * r)      # 0 → 180° through the resonance
    a1 = _amp1(rpm)
    rng = np.random.default_rng(seed)
    chans = []
    truth = {}
    for b, ang in LAYOUT:
        al = math.radians(ang)
        x1 = a1 * (np.cos(th - lag1) * math.cos(al) + ellipticity * np.sin(th - lag1) * math.sin(al))
        x2 = 3.0 * np.cos(2 * th - math.radians(40.0 + 10 * b))
        gap_x, gap_y = 100.0 * b, -200.0 + 50.0 * (rpm - rpm0) / (rpm1 - rpm0)
        dc = gap_x * math.cos(al) + gap_y * math.sin(al)
        chans.append(ProbeChannel(b, ang, "um", x1 + x2 + dc + noise_um * rng.standard_normal(t.size)))
        # Re(C e^{jθ}) with C = a e^{−j lag} (cos α − j e sin α)
        truth[(b, ang)] = (lambda s, al=al: _amp1(s) * np.exp(-1j * np.interp(s, rpm, lag1))
                           * (math.cos(al) - 1j * ellipticity * math.sin(al)),
                           3.0 * np.exp(-1j * math.radians(40.0 + 10 * b)))
    rec = Recording(sample_rate_hz=FS, channels=chans, keyphasor_times_s=kp[kp > 0] if keyphasor else None,
                    clearance_um=400.0)
    return rec, truth, rpm


def test_tracked_1x_2x_match_the_known_vectors():
    rec, truth, _ = _synthetic()
    tr = T.track_orders(rec)
    assert tr.kind == "run-up" and tr.phase_referenced and tr.speed_source == "keyphasor"
    for p, key in enumerate(tr.probes):
        want1 = truth[key][0](tr.speed_rpm)
        got1 = tr.vectors_um[:, p, 0]
        assert np.max(np.abs(np.abs(got1) / np.abs(want1) - 1)) < 0.01
        assert np.degrees(np.max(np.abs(np.angle(got1 / want1)))) < 1.0
        assert np.allclose(tr.amp_um_pp[:, p, 0], 2 * np.abs(got1))
        lag = np.mod(-np.degrees(np.angle(want1)), 360.0)
        assert np.max(np.abs((tr.phase_lag_deg[:, p, 0] - lag + 180.0) % 360.0 - 180.0)) < 1.0
        # 2X: right to 1 % of itself plus the leak of the fast-turning 1X through the critical (the fit holds each
        # vector constant over a revolution): at most 0.5 % of the 1X
        err2 = np.abs(tr.vectors_um[:, p, 1] - truth[key][1])
        assert np.all(err2 <= 0.01 * abs(truth[key][1]) + 0.005 * np.abs(want1))
    # the resonance: peak within 1 % of 1500 r/min (the model above peaks at 1500/√(1 − 2ζ²))
    pk = tr.peaks(1)
    assert len(pk) == 4 and all(abs(q["speed_rpm"] / 1500.0 - 1) < 0.01 for q in pk)
    # the 2X is flat: no resonance peak reported
    assert tr.peaks(2) == []


def test_centreline_recovers_the_gap_path():
    rec, _, _ = _synthetic()
    tr = T.track_orders(rec)
    cl = T.centreline(rec, tr)
    assert np.allclose(cl.x_um[:, 0], 100.0, atol=0.5) and np.allclose(cl.x_um[:, 1], 200.0, atol=0.5)
    assert cl.y_um[0, 0] == pytest.approx(-200.0, abs=1.0) and cl.y_um[-1, 0] == pytest.approx(-150.0, abs=1.0)
    bottom = T.centreline(rec, tr, reference="slow roll at the bottom")
    assert bottom.y_um[0, 0] == pytest.approx(-400.0, abs=1.0) and bottom.x_um[0, 0] == pytest.approx(0.0, abs=0.5)


def test_full_spectrum_puts_forward_whirl_at_positive_frequency():
    rec, _, _ = _synthetic()
    tr = T.track_orders(rec)
    fsp = T.full_spectrum(rec, tr, 1, max_slices=5)
    for i, s in enumerate(fsp.speed_rpm):
        f1 = s / 60.0
        pos = fsp.amp_um_pp[i][np.argmin(np.abs(fsp.frequencies_hz - f1))]
        neg = fsp.amp_um_pp[i][np.argmin(np.abs(fsp.frequencies_hz + f1))]
        # the ellipse (a, a/2) forward: a forward circle of radius 3a/4 and a reverse one of a/4, read pk-pk
        a = _amp1(np.array([s]))[0]
        assert pos == pytest.approx(1.5 * a, rel=0.2) and neg == pytest.approx(0.5 * a, rel=0.2)
        assert pos / neg == pytest.approx(3.0, rel=0.1)


def test_without_keyphasor_the_speed_is_tracked_and_phases_not_reported():
    rec, _, _ = _synthetic(noise_um=0.3, keyphasor=False)
    tr = T.track_orders(rec)
    assert tr.speed_source == "signal" and not tr.phase_referenced
    assert np.all(np.isnan(tr.phase_lag_deg))
    assert any("not referenced" in n for n in tr.notes)
    keep = ~tr.in_doubt
    # the tracked step speeds follow the true ramp
    t_true = tr.time_s[keep]
    assert np.max(np.abs(tr.speed_rpm[keep] - (900.0 + 40.0 * t_true))) < 10.0
    pk = tr.peaks(1)
    assert pk and all(abs(q["speed_rpm"] / 1500.0 - 1) < 0.03 for q in pk)


def test_without_keyphasor_a_circular_1x_is_refused_as_ambiguous():
    """A forward circular 1X orbit is what oil whirl looks like: the steady estimator says it cannot tell, and so
    does the tracking (no speed is made up)."""
    rec, _, _ = _synthetic(keyphasor=False, ellipticity=1.0, dur_s=10.0, rpm1=1300.0)
    with pytest.raises(ValueError, match="cannot be tracked from the signal.*ambiguous|cannot be tracked from the signal"):
        T.track_orders(rec)


def test_without_keyphasor_noise_alone_is_refused_not_guessed():
    rng = np.random.default_rng(3)
    chans = [ProbeChannel(b, a, "um", rng.standard_normal(int(10 * FS))) for b, a in LAYOUT]
    with pytest.raises(ValueError, match="cannot be tracked from the signal"):
        T.track_orders(Recording(sample_rate_hz=FS, channels=chans))


def test_keyphasor_dropping_out_mid_run_is_refused_with_where():
    rec, _, _ = _synthetic()
    kp = np.asarray(rec.keyphasor_times_s)
    gap = np.delete(kp, np.arange(300, 306))            # six pulses lost in the middle
    from dataclasses import replace

    with pytest.raises(ValueError, match=r"keyphasor drops out: the pulse interval at t = \d"):
        T.track_orders(replace(rec, keyphasor_times_s=gap))
    with pytest.raises(ValueError, match="keyphasor drops out: the last pulse"):
        T.track_orders(replace(rec, keyphasor_times_s=kp[: kp.size // 2]))


def test_a_ramp_that_reverses_is_refused():
    t = np.arange(int(20 * FS)) / FS
    rpm = np.where(t < 10, 1000 + 100 * t, 2000 - 100 * (t - 10))
    th = 2 * np.pi * np.cumsum(rpm / 60.0) / FS
    k = np.arange(1, int(th[-1] / (2 * np.pi)))
    kp = np.interp(2 * np.pi * k, th, t)
    chans = [ProbeChannel(b, a, "um", 10 * np.cos(th - math.radians(a))) for b, a in LAYOUT]
    with pytest.raises(ValueError, match=r"the speed reverses at t = (9|10)\.\d+ s"):
        T.track_orders(Recording(sample_rate_hz=FS, channels=chans, keyphasor_times_s=kp))


@pytest.mark.parametrize("suffix", [".csv", ".npy", ".h5", ".uff", ".json"])
def test_every_reader_format_tracks_the_same(tmp_path: Path, suffix: str):
    from rotordiag.models.transient_cli import read_transient
    from rotordiag.simulator.cli import write_probes

    rec, _, _ = _synthetic(dur_s=8.0, rpm1=1300.0)
    t, th, kp, _ = _ramp(900.0, 1300.0, 8.0)
    sig = np.zeros(t.size)
    for tk in kp[1:]:   # a notch from each mark, its edge a straight line through −½ at the mark (as a probe sees it)
        near = (t >= tk - 1.0 / FS) & (t < tk + 0.004)
        sig[near] = -np.clip(0.5 * (t[near] - tk) * FS + 0.5, 0.0, 1.0)
    w = np.array([c.data for c in rec.channels])
    path = tmp_path / f"run{suffix}"
    if suffix == ".json":   # the /diagnose body: pulse times, not a pulse channel
        import json

        body = {"sample_rate_hz": FS, "keyphasor_times_s": kp[1:].tolist(),
                "channels": [{"bearing": b, "angle_deg": a, "units": "um", "data": w[i].tolist()}
                             for i, (b, a) in enumerate(LAYOUT)]}
        path.write_text(json.dumps(body))
    else:
        write_probes(path, w, LAYOUT, FS, keyphasor_signal=sig)
    given = {"sample_rate_hz": FS, "channels": "1@45,1@135,2@45,2@135"}
    if suffix in (".npy", ".h5"):
        given["keyphasor_channel"] = "4"
    if suffix in (".csv", ".json"):
        given["channels"] = None
    res = read_transient(path, given)
    got = T.track_orders(res.recording)
    ref = T.track_orders(rec)
    n = min(got.speed_rpm.size, ref.speed_rpm.size)
    # pulses read from the raw channel are within a sample of the marks: vectors agree to 1 %, 2°
    off = int(np.argmin(np.abs(ref.time_s - got.time_s[0])))
    a, b = got.vectors_um[: n - off], ref.vectors_um[off:n]
    assert np.max(np.abs(np.abs(a) / np.abs(b) - 1)) < 0.01
    assert np.degrees(np.max(np.abs(np.angle(a / b)))) < 2.0


def test_a_1e8_sample_file_is_refused_before_it_is_read(tmp_path: Path):
    from numpy.lib import format as npformat

    from rotordiag.models.transient_cli import read_transient

    buf = io.BytesIO()
    npformat.write_array_header_1_0(buf, {"descr": "<f4", "fortran_order": False, "shape": (8, 10**8)})
    buf.write(np.zeros(16, np.float32).tobytes())
    p = tmp_path / "huge.npy"
    p.write_bytes(buf.getvalue())
    with pytest.raises(ValueError, match="more than the .* accepted"):
        read_transient(p, {"sample_rate_hz": 25600.0})


def test_plots_are_written_whole(tmp_path: Path):
    from rotordiag.features.plots import save_figures, transient_figures

    rec, _, _ = _synthetic(dur_s=10.0, rpm1=1800.0)
    tr = T.track_orders(rec)
    figs = transient_figures(rec, tr, orbit_speeds_rpm=[1000.0, 1500.0])
    paths = save_figures(figs, tmp_path)
    names = {p.stem for p in paths}
    assert {"bode", "polar", "waterfall_b1", "full_spectrum_b2", "centreline", "orbits"} <= names
    for p in paths:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not [q for q in tmp_path.iterdir() if q.name.startswith(".")]
    with pytest.raises(ValueError, match="the run covers"):
        T.orbits_at(rec, tr, [3000.0])


def test_plots_cli_refuses_a_keyphasor_that_stops_and_writes_nothing(tmp_path: Path):
    from typer.testing import CliRunner

    from rotordiag.cli import app
    from rotordiag.simulator.cli import write_probes

    rec, _, _ = _synthetic(dur_s=8.0, rpm1=1300.0)
    t, _, kp, _ = _ramp(900.0, 1300.0, 8.0)
    sig = np.zeros(t.size)
    for tk in kp[1: kp.size // 2]:                       # the pulses stop half-way through the run
        sig[(t >= tk) & (t < tk + 0.004)] = -1.0
    path = tmp_path / "stops.csv"
    write_probes(path, np.array([c.data for c in rec.channels]), LAYOUT, FS, keyphasor_signal=sig)
    out = tmp_path / "png"
    r = CliRunner().invoke(app, ["plots", str(path), "--out-dir", str(out)])
    assert r.exit_code == 2
    assert "keyphasor drops out: the last pulse is at t = " in r.output and "leave the keyphasor out" in r.output
    assert not out.exists()


def test_plots_in_mils_scale_every_length_and_say_so():
    import matplotlib.pyplot as plt

    from rotordiag.features.plots import bode_figure, centreline_figure

    rec, _, _ = _synthetic(dur_s=8.0, rpm1=1300.0)
    tr = T.track_orders(rec)
    um, mil = bode_figure(tr), bode_figure(tr, units="mil")
    a_um = um.axes[2].lines[0].get_ydata()       # 1X amplitude axis, first probe
    a_mil = mil.axes[2].lines[0].get_ydata()
    assert np.allclose(a_mil * 25.4, a_um) and "mil pk-pk" in mil.axes[2].get_ylabel()
    assert any("amplitude mil pk-pk" in t.get_text() for t in mil.texts)
    cl = centreline_figure(T.centreline(rec, tr), units="mil")
    assert "mil" in cl.axes[0].get_xlabel()
    with pytest.raises(ValueError, match="units must be 'um' or 'mil'"):
        bode_figure(tr, units="inch")
    for f in (um, mil, cl):
        plt.close(f)


def test_a_whirl_beside_1x_is_not_read_as_a_1x_peak():
    """A sub-synchronous whirl at 0.45X (20× the 1X) from t = 20 s: one revolution is one order wide, so the
    per-revolution fit would take much of it for 1X and report a 1X 'peak' there; those vectors jump from
    revolution to revolution and are left out, and the resonance at 1500 r/min is still the peak."""
    from dataclasses import replace

    rec, _, _ = _synthetic()
    t, th, _, _ = _ramp(900.0, 2100.0, 30.0)
    whirl = np.where(t > 20.0, 200.0, 0.0)
    chans = [replace(c, data=c.data + whirl * np.cos(0.45 * th - math.radians(c.angle_deg))) for c in rec.channels]
    tr = T.track_orders(replace(rec, channels=chans))
    late = tr.time_s > 20.5
    assert tr.readable()[late, :, 0].mean() < 0.1
    assert tr.readable()[tr.time_s < 19.0, :, 0].mean() > 0.95
    assert any(n.startswith("1X not readable") for n in tr.notes)
    pk = tr.peaks(1)
    assert pk and all(abs(q["speed_rpm"] / 1500.0 - 1) < 0.01 for q in pk)


def test_cascade_scales_keep_the_small_lines_and_say_how():
    """dB: a line 1000× (60 dB) below the largest is at the floor, one 10× (20 dB) below at 2/3 of the height;
    per row: every trace reaches full height; the plot states the scale; an unknown scale is refused."""
    from rotordiag.features.plots import _cascade_heights, waterfall_figure

    a = np.array([[1000.0, 1.0, 100.0], [10.0, 0.01, 1.0]])
    h, words = _cascade_heights(a, "db")
    assert h[0, 0] == pytest.approx(1.0) and h[0, 1] == pytest.approx(0.0) and h[0, 2] == pytest.approx(2 / 3)
    assert h[1, 0] == pytest.approx(1 / 3) and "dB" in words
    h, _ = _cascade_heights(a, "row")
    assert h.max(axis=1) == pytest.approx([1.0, 1.0]) and h[1, 2] == pytest.approx(0.1)
    h, _ = _cascade_heights(a, "linear")
    assert h[1, 0] == pytest.approx(0.01)
    with pytest.raises(ValueError, match="cascade scale 'log' is not one of"):
        _cascade_heights(a, "log")
    rec, _, _ = _synthetic(dur_s=6.0, rpm1=1300.0)
    wf = T.waterfall(rec, T.track_orders(rec), 0)
    fig = waterfall_figure(wf, scale="row")
    assert "each trace to its own largest line" in fig.axes[0].get_ylabel() + fig.axes[0].get_title()
    import matplotlib.pyplot as plt

    plt.close(fig)


def _huge_npy(path: Path) -> Path:
    """An NPY file whose header announces 8 channels × 10⁸ samples (3.2 GB) but which holds 64 bytes."""
    from numpy.lib import format as npformat

    buf = io.BytesIO()
    npformat.write_array_header_1_0(buf, {"descr": "<f4", "fortran_order": False, "shape": (8, 10**8)})
    buf.write(np.zeros(16, np.float32).tobytes())
    path.write_bytes(buf.getvalue())
    return path


def test_plots_cli_refuses_a_1e8_sample_file_and_writes_nothing(tmp_path: Path):
    from typer.testing import CliRunner

    from rotordiag.cli import app

    p = _huge_npy(tmp_path / "huge.npy")
    out = tmp_path / "png"
    r = CliRunner().invoke(app, ["plots", str(p), "--sample-rate-hz", "25600", "--keyphasor-channel", "7",
                                 "--out-dir", str(out)])
    assert r.exit_code == 2, r.output
    assert "(8, 100000000)" in r.output and "accepted" in r.output
    assert not out.exists()


def test_plots_cli_refuses_a_keyphasor_gap_mid_run_and_writes_nothing(tmp_path: Path):
    """Pulses missing for a stretch in the middle of the run, then back: exit 2 with where, no PNG."""
    from typer.testing import CliRunner

    from rotordiag.cli import app
    from rotordiag.simulator.cli import write_probes

    rec, _, _ = _synthetic(dur_s=8.0, rpm1=1300.0)
    t, _, kp, _ = _ramp(900.0, 1300.0, 8.0)
    sig = np.zeros(t.size)
    n = kp.size
    for tk in np.r_[kp[1: n // 2], kp[n // 2 + 3:]]:      # three pulses missing half-way
        sig[(t >= tk) & (t < tk + 0.004)] = -1.0
    path = tmp_path / "gap.csv"
    write_probes(path, np.array([c.data for c in rec.channels]), LAYOUT, FS, keyphasor_signal=sig)
    out = tmp_path / "png"
    r = CliRunner().invoke(app, ["plots", str(path), "--out-dir", str(out)])
    assert r.exit_code == 2, r.output
    assert "keyphasor drops out: the pulse interval at t = " in r.output
    assert not out.exists()
