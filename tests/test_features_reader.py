"""rotordiag.features.reader: the one recording reader (CSV / NPY / HDF5 / JSON), its conventions and its messages,
checked on the shipped example recordings and on files made from them."""
from __future__ import annotations

import io
import json

import h5py
import numpy as np
import pytest

from rotordiag.core.units import volts_to_um
from rotordiag.features import extract_features
from rotordiag.features.examples import example_path, list_examples
from rotordiag.features.reader import (
    ReadOptions,
    keyphasor_times_from_pulses,
    read_recording,
    recording_from_dict,
    sample_rate_from_times,
)
from rotordiag.features.safe_io import UnsafeFileError


def _csv(header, table, fmt="%.6g") -> bytes:
    buf = io.StringIO()
    buf.write(",".join(header) + "\n")
    np.savetxt(buf, table, delimiter=",", fmt=fmt)
    return buf.getvalue().encode()


@pytest.fixture(scope="module")
def example():
    res = read_recording(example_path("whirl.csv"))
    return res.recording


def test_examples_are_small_and_all_formats_agree(example):
    names = list_examples()
    assert {"aligned.csv", "whirl.csv", "whirl_2560hz.npy", "aligned.h5", "whirl.h5"} <= set(names)
    for n in names:
        assert example_path(n).stat().st_size < 400_000
    h5 = read_recording(example_path("whirl.h5")).recording
    npy = read_recording(example_path("whirl_2560hz.npy"), options=ReadOptions(sample_rate_hz=2560)).recording
    uff = read_recording(example_path("whirl.uff")).recording
    for other in (h5, npy, uff):
        assert other.sample_rate_hz == pytest.approx(example.sample_rate_hz, rel=1e-7)
        assert [(c.bearing, c.angle_deg) for c in other.channels] == [(c.bearing, c.angle_deg) for c in example.channels]
        for a, b in zip(other.channels, example.channels):
            np.testing.assert_allclose(a.data, b.data, atol=6e-4)   # CSV keeps 3 decimals of µm
    assert h5.speed_rpm is None or h5.speed_rpm > 0


def test_time_column_with_six_significant_digits_passes_and_gives_the_rate():
    fs = 2560.0
    t = np.arange(25_600) / fs                    # 10 s: 6 digits round to 5e-6 s, 1.3 % of a sample
    rate = sample_rate_from_times(np.array([float(f"{v:.6g}") for v in t]))
    assert rate == pytest.approx(fs, rel=1e-6)


def test_irregular_time_column_names_the_row(example):
    data = np.stack([c.data for c in example.channels]).T
    t = np.arange(data.shape[0]) / example.sample_rate_hz
    keep = np.r_[0:500, 501:data.shape[0]]            # one dropped sample
    body = _csv(["time_s"] + [f"b{c.bearing}@{c.angle_deg:g}" for c in example.channels],
                np.column_stack([t[keep], data[keep]]))
    with pytest.raises(ValueError, match=r"not evenly spaced \(data row 50[01]"):
        read_recording(body, filename="gap.csv")


def test_explicit_column_mapping_and_bad_header(example):
    data = np.stack([c.data for c in example.channels]).T[:, :4]
    t = np.arange(data.shape[0]) / example.sample_rate_hz
    body = _csv(["time_s", "GEN DE X", "GEN DE Y", "EXC DE X", "EXC DE Y", "spare"],
                np.column_stack([t, data, np.zeros(t.size)]))
    with pytest.raises(ValueError, match=r"\['GEN DE X', .*'spare'\] are neither a time column .* nor named "
                       r"BEARING@ANGLE.*not read as probes"):
        read_recording(body, filename="plant.csv")
    mapping = {"GEN DE X": "b1@45", "GEN DE Y": "b1@135", "EXC DE X": "b2@45", "EXC DE Y": "b2@135"}
    res = read_recording(body, filename="plant.csv", options=ReadOptions(channels=mapping))
    rec = res.recording
    assert "column(s) ['spare'] are neither time, keyphasor nor in the channel mapping: not read" in res.notes
    assert [(c.bearing, c.angle_deg) for c in rec.channels] == [(1, 45.0), (1, 135.0), (2, 45.0), (2, 135.0)]
    np.testing.assert_allclose(rec.channels[2].data, data[:, 2], atol=1e-3)
    with pytest.raises(ValueError, match="'GEN NDE X' is not a channel name of the CSV file"):
        read_recording(body, filename="plant.csv", options=ReadOptions(channels={"GEN NDE X": "b1@45"}))


def test_keyphasor_pulse_train_gives_the_pulse_times():
    fs, f_rot = 5000.0, 29.7
    t = np.arange(int(fs)) / fs
    true = np.arange(0.013, 1.0, 1 / f_rot)
    notch = np.zeros_like(t)
    for tp in true:          # a 1.5 ms notch with 0.2 ms ramps: -8 V gap, -16 V in the notch
        notch = np.maximum(notch, np.clip(np.minimum((t - tp) / 2e-4, (tp + 1.5e-3 - t) / 2e-4), 0, 1))
    v = -8.0 - 8.0 * notch + np.random.default_rng(1).normal(0, 0.05, t.size)
    got = keyphasor_times_from_pulses(v, fs, edge="falling")
    # the falling edge crosses −12 V halfway up its 0.2 ms ramp
    np.testing.assert_allclose(got, true[: got.size] + 1e-4, atol=0.2 / fs)
    assert got.size == true.size
    rising = keyphasor_times_from_pulses(v, fs, edge="rising")
    np.testing.assert_allclose(rising, true[: rising.size] + 1.5e-3 - 1e-4, atol=0.2 / fs)
    with pytest.raises(ValueError, match="flat"):
        keyphasor_times_from_pulses(np.zeros(100), fs)


def test_raw_keyphasor_column_in_a_csv(example):
    fs = example.sample_rate_hz
    data = np.stack([c.data for c in example.channels]).T
    n = data.shape[0]
    t = np.arange(n) / fs
    speed_hz = 1800 / 60
    phase = (t * speed_hz) % 1.0
    kp = np.where(phase < 0.05, -16.0, -8.0)          # notch once per revolution
    body = _csv(["time_s", "kp"] + [f"b{c.bearing}@{c.angle_deg:g}" for c in example.channels],
                np.column_stack([t, kp, data]))
    res = read_recording(body, filename="kp.csv")
    kpt = res.recording.keyphasor_times_s
    assert kpt is not None and np.allclose(np.diff(kpt), 1 / speed_hz, atol=1.0 / fs)
    assert any("keyphasor" in n for n in res.notes)
    assert len(res.recording.channels) == 8


def test_volts_with_sensitivity_and_gap_voltage(example):
    s, gap = 7.87, -10.0
    volts = np.stack([gap + s * c.data * 1e-3 for c in example.channels])    # toward the probe: less negative
    buf = io.BytesIO()
    np.save(buf, volts)
    rec = read_recording(buf.getvalue(), filename="v.npy",
                         options=ReadOptions(sample_rate_hz=2560, units="V", sensitivity_v_per_mm=s,
                                             gap_voltage_v=gap)).recording
    for a, b in zip(rec.channels, example.channels):
        np.testing.assert_allclose(a.data_um, b.data_um, atol=1e-9)
    with pytest.raises(ValueError, match="sensitivity"):
        read_recording(buf.getvalue(), filename="v.npy", options=ReadOptions(sample_rate_hz=2560, units="V"))
    assert volts_to_um(np.array([-9.0]), 7.87, -10.0)[0] == pytest.approx(1e3 / 7.87)


def test_mils_and_mm_give_the_same_recording(example):
    for unit, f in (("mil", 1 / 25.4), ("mm", 1e-3)):
        d = {"sample_rate_hz": 2560, "channels": [
            {"bearing": c.bearing, "angle_deg": c.angle_deg, "units": unit, "data": (c.data * f).tolist()}
            for c in example.channels]}
        rec = recording_from_dict(d).recording
        np.testing.assert_allclose(rec.xy_um(2), example.xy_um(2), rtol=1e-12, atol=1e-9)


def test_mirrored_installation_is_not_read_as_reverse_whirl(example):
    """Seen from the exciter end the probes sit at 180° − α and the shaft turns clockwise: stated as such,
    the reader gives back the forward whirl; read naively, the whirl comes out reversed."""
    mirrored = [f"b{c.bearing}@{(180.0 - c.angle_deg) % 360:g}" for c in example.channels]
    data = np.stack([c.data for c in example.channels])
    buf = io.BytesIO()
    np.save(buf, data)
    body = buf.getvalue()
    ref = extract_features(example).as_dict()
    told = read_recording(body, filename="m.npy", options=ReadOptions(
        sample_rate_hz=example.sample_rate_hz, channels=mirrored, viewed_from="non-driver", rotation="ccw"))
    naive = read_recording(body, filename="m.npy", options=ReadOptions(
        sample_rate_hz=example.sample_rate_hz, channels=mirrored))
    got, wrong = extract_features(told.recording).as_dict(), extract_features(naive.recording).as_dict()
    assert ref["b2_1x_whirl_dir"] == 1.0
    assert got["b2_1x_whirl_dir"] == 1.0 and got["b2_1x_whirl_index"] == pytest.approx(ref["b2_1x_whirl_index"])
    assert wrong["b2_1x_whirl_dir"] == -1.0
    assert any("mirrored" in n for n in told.notes)


def test_dataset_hdf5_row_and_channel_table(tmp_path, example):
    data = np.stack([c.data for c in example.channels]).astype(np.float32)
    p = tmp_path / "ds.h5"
    table = np.array([(c.bearing, c.angle_deg) for c in example.channels], dtype=[("bearing", "i1"), ("angle_deg", "f8")])
    with h5py.File(p, "w") as f:
        f.create_dataset("waveforms", data=np.stack([data * 0.5, data]), chunks=(1, 8, data.shape[1]), compression="gzip")
        f.create_dataset("channels", data=table[::-1])       # a layout other than the default: must be honoured
        f.create_dataset("done", data=np.array([True, True]))
        f.create_dataset("parameters/speed_rpm", data=np.array([1800.0, 1800.0]))
        f.create_dataset("labels/misalignment", data=np.array([0.0, 0.5]))
        f.attrs["sample_rate_hz"] = 2560.0
        f.attrs["waveform_units"] = "um"
    with pytest.raises(ValueError, match="dataset with 2 samples; choose one"):
        read_recording(p)
    res = read_recording(p, options=ReadOptions(sample_index=1))
    assert [(c.bearing, c.angle_deg) for c in res.recording.channels] == [tuple(r) for r in table[::-1].tolist()]
    assert res.truth == {"misalignment": 0.5} and res.recording.speed_rpm == 1800.0
    with pytest.raises(ValueError, match="outside the file's samples"):
        read_recording(p, options=ReadOptions(sample_index=5))


@pytest.mark.parametrize("body, name, needle", [
    (b"", "x.csv", "empty"),
    (b"b1@45,b1@135\n1,2\n3\n", "x.csv", "has 1 values"),
    (b"b1@45,b1@135\n1,oops\n", "x.csv", "not a number"),
    (b"\x89HDF\r\n\x1a\n" + b"\0" * 64, "x.h5", "HDF5"),
    (b"\x93NUMPY" + b"\0" * 10, "x.npy", "NPY"),
    (b'{"sample_rate_hz": NaN, "channels": []}', "x.json", "NaN"),
    (b"hello", "x.wav", "unknown file type"),
])
def test_bad_files_say_what_to_fix(body, name, needle):
    with pytest.raises(ValueError, match=needle):
        read_recording(body, filename=name)


def test_hdf5_with_an_external_link_is_refused(tmp_path):
    p = tmp_path / "evil.h5"
    with h5py.File(p, "w") as f:
        f["waveforms"] = h5py.ExternalLink("/etc/passwd", "/x")
    with pytest.raises(UnsafeFileError):
        read_recording(p)


def test_json_file_and_recording_from_dict_agree(tmp_path, example):
    d = {"sample_rate_hz": example.sample_rate_hz, "speed_rpm": 1800.0, "channels": [
        {"bearing": c.bearing, "angle_deg": c.angle_deg, "units": "um", "data": c.data.tolist()}
        for c in example.channels]}
    p = tmp_path / "r.json"
    p.write_text(json.dumps(d))
    a, b = read_recording(p).recording, recording_from_dict(d).recording
    assert a.speed_rpm == b.speed_rpm == 1800.0
    np.testing.assert_array_equal(a.channels[3].data, example.channels[3].data)


def test_spelled_out_header_names_with_units(example):
    data = np.stack([c.data for c in example.channels]).T / 25.4
    names = [f"b{c.bearing}_{c.angle_deg:g}deg_mil" for c in example.channels]
    rec = read_recording(_csv(names, data, fmt="%.8g"), filename="mils.csv",
                         options=ReadOptions(sample_rate_hz=2560)).recording
    assert rec.channels[0].units == "mil"
    np.testing.assert_allclose(rec.xy_um(3), example.xy_um(3), atol=1e-4)


def test_volts_without_the_gap_voltage_carry_no_centreline(example):
    """Each channel's mean voltage taken as its gap removes the DC part: the recording says so, and the centreline
    features are missing rather than a journal read at the bearing centre."""
    from rotordiag.features import extract_features

    s, gap = 7.87, -10.0
    volts = np.stack([gap + s * c.data * 1e-3 for c in example.channels])
    buf = io.BytesIO()
    np.save(buf, volts)
    with_gap = read_recording(buf.getvalue(), filename="v.npy", options=ReadOptions(
        sample_rate_hz=2560, units="V", sensitivity_v_per_mm=s, gap_voltage_v=gap, clearance_um=350.0))
    without = read_recording(buf.getvalue(), filename="v.npy", options=ReadOptions(
        sample_rate_hz=2560, units="V", sensitivity_v_per_mm=s, clearance_um=350.0))
    assert not with_gap.recording.dc_removed and without.recording.dc_removed
    assert any("no shaft position" in n for n in without.notes)
    fr_gap, fr = extract_features(with_gap.recording), extract_features(without.recording)
    for b in (1, 2, 3, 4):
        assert np.isfinite(fr_gap[f"b{b}_centre_ecc_per_c"]) and np.isnan(fr[f"b{b}_centre_ecc_per_c"])
        assert fr[f"b{b}_1x_major_pp_per_c"] == pytest.approx(fr_gap[f"b{b}_1x_major_pp_per_c"], rel=1e-9)
