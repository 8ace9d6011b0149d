"""Validation, invariance (probe angles, units, sample rate), clearance, missing bearings, schema."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from rotordiag.features import FEATURE_NAMES, FEATURE_SPECS, ProbeChannel, Recording, extract_features

from .test_features_synth import keyphasor_times, make_recording

RPM = 1953.7
PHASE = re.compile(r"_deg$")


def _assert_same_features(a, b, rtol=1e-9, atol=1e-9, skip=()):
    assert a.names == b.names
    for name, va, vb in zip(a.names, a.values, b.values):
        if any(s in name for s in skip):
            continue
        if np.isnan(va) or np.isnan(vb):
            assert np.isnan(va) and np.isnan(vb), name
        elif PHASE.search(name):
            assert abs((va - vb + 180) % 360 - 180) < 1e-6, (name, va, vb)
        else:
            assert vb == pytest.approx(va, rel=rtol, abs=atol), name


# ----------------------------------------------------------------------------- invariance
@pytest.mark.parametrize("angles", [(0.0, 90.0), (90.0, 0.0), (-45.0, 45.0), (30.0, 120.0), (10.0, 70.0)])
def test_probe_angle_convention_does_not_change_features(angles):
    ref = extract_features(make_recording(angles=(45.0, 135.0), speed_rpm=RPM))
    fr = extract_features(make_recording(angles=angles, speed_rpm=RPM))
    _assert_same_features(ref, fr)


@pytest.mark.parametrize("units", ["mil", "mm", "m"])
def test_units_do_not_change_features(units):
    ref = extract_features(make_recording(speed_rpm=RPM, clearance_um=350.0))
    fr = extract_features(make_recording(speed_rpm=RPM, clearance_um=350.0, units=units))
    _assert_same_features(ref, fr)


def test_units_invariance_holds_for_estimated_speed_with_noise():
    ref = extract_features(make_recording(noise_um=0.8, seed=3))
    fr = extract_features(make_recording(noise_um=0.8, seed=3, units="mil"))
    assert fr.speed_rpm == pytest.approx(ref.speed_rpm, rel=1e-9)
    _assert_same_features(ref, fr, rtol=1e-6, atol=1e-8)


def test_sample_rate_does_not_change_features():
    """5 kHz vs 12.8 kHz over the same 3.2 s, with a 0.414X whirl: orders exact, bands within 1 %."""
    def whirl(t, b):
        th = 2 * np.pi * (np.sqrt(2) - 1) * RPM / 60 * t
        return 6 * np.cos(th), 6 * np.sin(th)

    a = extract_features(make_recording(fs=5120.0, n=16384, extra=whirl, speed_rpm=RPM))
    b = extract_features(make_recording(fs=12800.0, n=40960, extra=whirl, speed_rpm=RPM))
    exact = [n for n in FEATURE_NAMES if re.search(r"_[123]x_|1x_|2x_|3x_|dphase", n)
             and "direct" not in n and "per_c" not in n]
    for name in exact:
        va, vb = a[name], b[name]
        if PHASE.search(name):
            assert abs((va - vb + 180) % 360 - 180) < 0.01, name
        else:
            assert vb == pytest.approx(va, rel=2e-4, abs=1e-6), name
    for name in FEATURE_NAMES:
        if any(k in name for k in ("subsync", "whirl_band", "nonsync", "direct", "poincare", "orbit12")):
            if np.isfinite(a[name]):
                assert b[name] == pytest.approx(a[name], rel=0.01, abs=1e-3), name
    assert a["motion_quasi_periodic"] == b["motion_quasi_periodic"] == 1.0


def test_keyphasor_and_given_speed_agree_when_consistent():
    a = extract_features(make_recording(speed_rpm=RPM))
    b = extract_features(make_recording(keyphasor_times_s=keyphasor_times(RPM, 3.2)))
    exact = [n for n in FEATURE_NAMES if "amp_um_pp" in n or "ratio" in n or "dphase" in n]
    for name in exact:
        assert b[name] == pytest.approx(a[name], rel=1e-6, abs=1e-6, nan_ok=True), name


# ----------------------------------------------------------------------------- clearance, bearings
def test_clearance_scalar_and_per_bearing():
    fr = extract_features(make_recording(speed_rpm=RPM, clearance_um={2: 350.0, 3: 200.0}))
    assert fr["b2_x_1x_amp_pp_per_c"] == pytest.approx(fr["b2_x_1x_amp_um_pp"] / 350.0, rel=1e-12)
    assert fr["b3_orbit12_pp_per_c"] == pytest.approx(fr["b3_orbit12_um_pp"] / 200.0, rel=1e-12)
    assert fr["b3_orbit12_area_per_c2"] == pytest.approx(fr["b3_orbit12_area_um2"] / 200.0 ** 2, rel=1e-12)
    assert np.isnan(fr["b1_x_1x_amp_pp_per_c"]) and np.isnan(fr["b4_subsync_rms_per_c"])
    fr2 = extract_features(make_recording(speed_rpm=RPM))
    per_c = [n for n in FEATURE_NAMES if "_per_c" in n]
    assert per_c and all(np.isnan(fr2[n]) for n in per_c)
    assert all(np.isfinite(fr2[n]) for n in FEATURE_NAMES if "amp_um_pp" in n)


def test_centreline_features_are_the_static_position_in_clearances():
    fr = extract_features(make_recording(speed_rpm=RPM, offset_um=(-70.0, -140.0), clearance_um=350.0))
    for b in (2, 3):
        assert fr[f"b{b}_centre_x_per_c"] == pytest.approx(-0.2, abs=2e-3)
        assert fr[f"b{b}_centre_y_per_c"] == pytest.approx(-0.4, abs=2e-3)
        assert fr[f"b{b}_centre_ecc_per_c"] == pytest.approx(np.hypot(0.2, 0.4), abs=2e-3)
    # A DC part of 2 clearances is a raw probe gap, not a position: missing, not a number.
    gap = extract_features(make_recording(speed_rpm=RPM, offset_um=(0.0, 700.0), clearance_um=350.0))
    assert np.isnan(gap["b2_centre_y_per_c"]) and np.isnan(gap["b2_centre_ecc_per_c"])
    unknown = extract_features(make_recording(speed_rpm=RPM, offset_um=(-70.0, -140.0)))
    assert np.isnan(unknown["b2_centre_x_per_c"])


def test_missing_bearings_give_nan_columns_in_the_same_schema():
    comps = {2: [(1, 30.0, 10.0, 25.0, 100.0), (2, 10.0, 50.0, 8.0, 140.0)],
             3: [(1, 20.0, 200.0, 18.0, 290.0), (2, 6.0, 30.0, 5.0, 120.0)]}
    fr = extract_features(make_recording(components=comps, speed_rpm=RPM))
    assert fr.names == FEATURE_NAMES
    assert sorted(fr.bearings) == [2, 3]
    assert all(np.isnan(fr[n]) for n in FEATURE_NAMES if n.startswith(("b1_", "b4_")))
    assert fr["dphase_1x_b2_b3_x_deg"] == pytest.approx(10.0 - 200.0 + 360.0, abs=1e-6)
    assert np.isnan(fr["dphase_1x_b1_b2_x_deg"]) and np.isnan(fr["dphase_2x_b3_b4_y_deg"])
    assert fr["b2_x_1x_amp_um_pp"] == pytest.approx(60.0, rel=1e-9)


def test_schema_documented_with_units():
    assert len(FEATURE_NAMES) == len(set(FEATURE_NAMES))
    assert all(s.unit and s.definition for s in FEATURE_SPECS)
    doc = (Path(__file__).resolve().parents[1] / "docs" / "features.md").read_text()
    for name in FEATURE_NAMES:
        generic = re.sub(r"^b[1-4]_", "b1_", name)
        assert f"`{generic}`" in doc, f"{name} is not documented in docs/features.md"
    from rotordiag.features._names import markdown_table

    assert markdown_table() in doc, "docs/features.md's schema table differs from features._names.markdown_table()"


def test_as_dict_and_getitem():
    fr = extract_features(make_recording(speed_rpm=RPM))
    d = fr.as_dict()
    assert all(type(v) is float for v in d.values())
    assert d["b2_x_1x_amp_um_pp"] == fr["b2_x_1x_amp_um_pp"]
    with pytest.raises(KeyError, match="FEATURE_NAMES"):
        fr["b2_x_9x_amp_um_pp"]


# ----------------------------------------------------------------------------- validation
def _chans(n=8192, bearings=(2,), angles=(45.0, 135.0), units="um"):
    t = np.arange(n) / 5120.0
    s = 10 * np.cos(2 * np.pi * RPM / 60 * t)
    return [ProbeChannel(b, a, units, s.copy()) for b in bearings for a in angles]


def test_bad_units_name_the_allowed_ones():
    with pytest.raises(ValueError, match=r"units 'inch'.*'um', 'mm', 'm', 'mil'"):
        ProbeChannel(1, 45.0, "inch", np.zeros(100))


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_samples_refused(bad):
    d = np.zeros(1000)
    d[17] = bad
    with pytest.raises(ValueError, match="non-finite.*index 17"):
        ProbeChannel(1, 45.0, "um", d)


def test_bearing_number_checked():
    """Bearings are numbered 1–8 along a train (a three-rotor train has six); beyond, zero or not an integer: refused."""
    for bad in (9, 0, 2.0, True):
        with pytest.raises(ValueError, match="bearing must be a bearing number 1–8"):
            ProbeChannel(bad, 45.0, "um", np.zeros(100))
    assert ProbeChannel(5, 45.0, "um", np.zeros(100)).bearing == 5


def test_mismatched_lengths_refused():
    c = _chans()
    c[1] = ProbeChannel(2, 135.0, "um", c[1].data[:-5])
    with pytest.raises(ValueError, match="different lengths"):
        Recording(5120.0, c)


def test_bearing_without_both_probes_refused():
    c = _chans(bearings=(2, 3))[:3]
    with pytest.raises(ValueError, match="bearing 3 has 1 probe"):
        Recording(5120.0, c)


def test_parallel_probes_refused():
    with pytest.raises(ValueError, match="parallel"):
        Recording(5120.0, _chans(angles=(45.0, 225.0)))


def test_too_few_revolutions_refused_with_the_needed_duration():
    n = int(7.5 * 5120 / (RPM / 60))
    with pytest.raises(ValueError, match=r"at least 8 whole revolutions.*record at least 0\.24"):
        extract_features(Recording(5120.0, _chans(n=n), speed_rpm=RPM))


def test_sample_rate_too_low_for_3x_refused():
    with pytest.raises(ValueError, match="samples per revolution.*sample_rate_hz >="):
        extract_features(Recording(200.0, _chans(n=4096), speed_rpm=RPM))


@pytest.mark.parametrize("kw,match", [
    (dict(sample_rate_hz=-1.0), "sample_rate_hz must be between 1 and 1e\\+06 Hz"),
    (dict(sample_rate_hz=5e-324), "sample_rate_hz must be between .* check the units"),
    (dict(sample_rate_hz=1e308), "sample_rate_hz must be between .* check the units"),
    (dict(sample_rate_hz=float("nan")), "sample_rate_hz must be between"),
    (dict(speed_rpm=0.0), "speed_rpm must be between 1 and 100000 r/min"),
    (dict(speed_rpm=5e-324), "speed_rpm must be between .* check the units"),
    (dict(speed_rpm=-0.0), "speed_rpm must be between"),
    (dict(keyphasor_times_s=[0.1, 0.05, 0.2]), "strictly increasing"),
    (dict(keyphasor_times_s=[[0.1, 0.2]]), "1-D array"),
    (dict(keyphasor_times_s=[0.0, 5e-324, 1e-323]), "at least 1e-06 s apart: check the units"),
    (dict(keyphasor_times_s=[0.0, 1e300]), "within ±1e\\+07 s"),
    (dict(clearance_um=-3.0), "clearance_um must be between 1 and 100000 µm"),
    (dict(clearance_um=5e-324), "clearance_um must be between"),
    (dict(speed_range_rpm=(5e-324, 3000.0)), "speed_range_rpm must lie between 1 and 100000 r/min"),
    (dict(clearance_um={9: 300.0}), "not a bearing number"),
])
def test_recording_fields_validated(kw, match):
    args = dict(sample_rate_hz=5120.0, channels=_chans())
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        Recording(**args)


def test_keyphasor_off_the_record_refused():
    with pytest.raises(ValueError, match="on the samples' clock"):
        extract_features(Recording(5120.0, _chans(), keyphasor_times_s=np.arange(100.0, 110.0, 0.03)))


def test_empty_channels_refused():
    with pytest.raises(ValueError, match="channels is empty"):
        Recording(5120.0, [])


def test_dc_gap_offset_does_not_change_features():
    """Probes read the gap: a 1 mm DC offset changes only the mean position in the details."""
    ref = extract_features(make_recording(speed_rpm=RPM, noise_um=0.3, seed=4))
    fr = extract_features(make_recording(speed_rpm=RPM, noise_um=0.3, seed=4, offset_um=(1000.0, -750.0)))
    _assert_same_features(ref, fr, rtol=1e-7, atol=1e-7)
    assert fr.bearings[2].mean_um == pytest.approx((1000.0, -750.0), abs=0.05)


def test_keyphasor_poincare_points_period_2():
    """With a keyphasor starting mid-record, once-per-rev points alternate for a 1/2X component."""
    f1, t0 = RPM / 60, 0.0371

    def half(t, b):
        th = 2 * np.pi * f1 * (t - t0)
        return 4 * np.cos(0.5 * th), 4 * np.sin(0.5 * th)

    rec = make_recording(theta_fn=lambda t: 2 * np.pi * f1 * (t - t0), extra=half,
                         keyphasor_times_s=keyphasor_times(RPM, 3.2, t0))
    fr = extract_features(rec)
    assert fr["motion_period"] == 2.0
    pts = fr.bearings[3].poincare_um
    np.testing.assert_allclose(pts[0] - pts[1], [8.0, 0.0], atol=1e-3)   # x alternates ±4 µm
    assert fr["b3_poincare_rms_um"] == pytest.approx(4.0, rel=1e-3)


def test_concurrent_extractions_agree_and_restore_blas_threads():
    """Threads share the per-thread scratch buffers safely and leave the BLAS setting as found."""
    from concurrent.futures import ThreadPoolExecutor

    from threadpoolctl import threadpool_info

    before = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    recs = [make_recording(speed_rpm=RPM, noise_um=0.5, seed=s) for s in range(4)]
    serial = [extract_features(r).values for r in recs]
    with ThreadPoolExecutor(max_workers=4) as pool:
        parallel = list(pool.map(lambda r: extract_features(r).values, recs * 3))
    for i, v in enumerate(parallel):
        # equal up to the last bits (buffer alignment can change SIMD summation order)
        np.testing.assert_allclose(v, serial[i % 4], rtol=1e-12, atol=1e-12)
    after = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    assert after == before
