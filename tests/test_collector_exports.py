"""Exports as they come: time columns in any common spelling, probe voltages (V, mV) with the sensitivity as
datasheets state it, column names mapped to bearings, metadata blocks skipped — checked on recordings written
the way three collector/DAQ exports write them (tests/collector_exports.py), through the reader, the CLI and
HTTP, against the same waveforms sent as µm with the layout stated."""
from __future__ import annotations

import io
import json

import numpy as np
import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from rotordiag.cli import app as cli_app
from rotordiag.core.units import sensitivity_v_per_mm
from rotordiag.features import extract_features
from rotordiag.features.examples import example_path
from rotordiag.features.reader import ReadOptions, parse_channel_map, read_recording
from rotordiag.service.main import create_app
from tests.collector_exports import (
    DAQ_SENSITIVITY,
    GAP_V,
    LAYOUT,
    LVM_SENSITIVITY,
    mapping,
    write_collector_export,
    write_daq_csv,
    write_lvm,
)
from tests.service_util import make_settings, shipped_or_tiny_registry

LAYOUT_TEXT = ",".join(f"{b}@{a:g}" for b, a in LAYOUT)


@pytest.fixture(scope="module")
def reference():
    """The shipped severe example (µm, b1@45 … b4@135): what every export below holds."""
    rec = read_recording(example_path("whirl.csv")).recording
    return rec, np.stack([c.data for c in rec.channels])


#: the three exports: writer, file name, what the user states beside the file (CLI option → value)
EXPORTS = {
    "labview_lvm": (write_lvm, "run.lvm", {"sensitivity": LVM_SENSITIVITY, "gap_voltage_v": GAP_V}),
    "daq_csv_ms_unit_row": (write_daq_csv, "daq.csv", {"sensitivity": DAQ_SENSITIVITY, "gap_voltage_v": GAP_V}),
    "collector_metadata_block": (write_collector_export, "collector.txt", {}),
}


@pytest.fixture(scope="module")
def exports(tmp_path_factory, reference):
    rec, data = reference
    d = tmp_path_factory.mktemp("exports")
    out = {}
    for key, (writer, name, stated) in EXPORTS.items():
        names = writer(d / name, data, rec.sample_rate_hz)
        out[key] = (d / name, mapping(names), stated)
    return out


@pytest.mark.parametrize("key", list(EXPORTS))
def test_each_export_reads_as_the_same_waveforms_in_um(exports, reference, key):
    rec, data = reference
    path, channel_map, stated = exports[key]
    opts = ReadOptions(channels=parse_channel_map(channel_map),
                       sensitivity_v_per_mm=stated.get("sensitivity"), gap_voltage_v=stated.get("gap_voltage_v"))
    res = read_recording(path, options=opts)
    got = res.recording
    assert got.sample_rate_hz == pytest.approx(rec.sample_rate_hz, rel=1e-6)
    assert [(c.bearing, c.angle_deg) for c in got.channels] == LAYOUT
    # written with 6 decimals of V, 3 of mV, 5 of mil: at most 0.13, 0.06, 0.13 nm of rounding
    np.testing.assert_allclose(np.stack([c.data_um for c in got.channels]), data, atol=1e-3)
    if key == "daq_csv_ms_unit_row":
        assert "column(s) ['BRG 2 TEMP'] are neither time, keyphasor nor in the channel mapping: not read" in res.notes
        assert any("time column 'Time [ms]'" in n for n in res.notes)
    if key == "collector_metadata_block":
        assert "column(s) ['Sample'] are neither time, keyphasor nor in the channel mapping: not read" in res.notes
        assert "sample rate 2560 Hz from the file's header line 'Sample Rate'" in res.notes
        assert "units mil from the header line 'Units'" in res.notes
    if key == "labview_lvm":
        assert any("units V from the header line 'Y_Unit_Label'" in n for n in res.notes)
        assert got.channels[0].declared_as == "V at 7.87 V/mm, gap -10 V"
        assert not got.dc_removed                    # the gap voltage was given: the DC part is a position


@pytest.mark.parametrize("key", ["labview_lvm", "daq_csv_ms_unit_row"])
def test_probe_voltages_need_the_sensitivity(exports, key):
    path, channel_map, _ = exports[key]
    with pytest.raises(ValueError, match=r"units m?V: give the probe sensitivity \(e.g. '7.87 V/mm', '200 mV/mil'"):
        read_recording(path, options=ReadOptions(channels=parse_channel_map(channel_map)))


def test_without_a_mapping_the_export_columns_are_refused_by_name(exports):
    path, _, stated = exports["daq_csv_ms_unit_row"]
    with pytest.raises(ValueError, match=r"\['GEN NDE X', .*'BRG 2 TEMP'\] are neither a time column"):
        read_recording(path, options=ReadOptions(sensitivity_v_per_mm=DAQ_SENSITIVITY))


@pytest.mark.parametrize("datasheet, v_per_mm", [
    ("7.87 V/mm", 7.87), ("200 mV/mil", 0.2 / 0.0254), ("7.87 mV/um", 7.87), ("7.87 mV/µm", 7.87),
    ("0.2 V/mil", 0.2 / 0.0254), (7.87, 7.87), ("3.94", 3.94), ("100 mV/mil", 0.1 / 0.0254)])
def test_sensitivity_as_datasheets_state_it(datasheet, v_per_mm):
    assert sensitivity_v_per_mm(datasheet) == pytest.approx(v_per_mm, rel=1e-12)


@pytest.mark.parametrize("bad", ["200 mV", "7.87 V/inch", "-7.87 V/mm", "0", "fast"])
def test_a_sensitivity_that_is_not_one_says_how_to_write_it(bad):
    with pytest.raises(ValueError, match="probe sensitivity"):
        sensitivity_v_per_mm(bad)


def _table(header, rows, delim=","):
    buf = io.StringIO()
    for line in header:
        buf.write(delim.join(line) + "\n")
    np.savetxt(buf, rows, delimiter=delim, fmt="%.9g")
    return buf.getvalue().encode()


@pytest.mark.parametrize("name, unit_row, factor", [
    ("Time (s)", None, 1.0), ("Time [ms]", None, 1e3), ("t_s", None, 1.0), ("time_us", None, 1e6),
    ("TIME/s", None, 1.0), ("Time(sec)", None, 1.0), ("Time [µs]", None, 1e6), ("time", "ms", 1e3),
    ("X_Value", None, 1.0), ("Elapsed Time", "[s]", 1.0)])
def test_time_columns_in_any_common_spelling_give_the_rate(reference, name, unit_row, factor):
    rec, data = reference
    t = np.arange(data.shape[1]) / rec.sample_rate_hz * factor
    header = [[name, *(f"b{b}@{a:g}" for b, a in LAYOUT)]]
    if unit_row is not None:
        header.append([unit_row, *(["um"] * len(LAYOUT))])
    res = read_recording(_table(header, np.column_stack([t, data.T])), filename="x.csv")
    assert res.recording.sample_rate_hz == pytest.approx(rec.sample_rate_hz, rel=1e-6)
    assert len(res.recording.channels) == 8                       # the time column is no 9th probe


def test_an_uneven_time_column_in_ms_is_refused_with_the_row(reference):
    rec, data = reference
    t = np.arange(data.shape[1]) / rec.sample_rate_hz * 1e3
    t[100:] += 1e3 / rec.sample_rate_hz                           # a dropped sample at row 101
    with pytest.raises(ValueError, match=r"not evenly spaced \(data row 101.*dropped or repeated sample"):
        read_recording(_table([["Time [ms]", *(f"b{b}@{a:g}" for b, a in LAYOUT)]], np.column_stack([t, data.T])),
                       filename="x.csv")
    with pytest.raises(ValueError, match=r"time column 'Time \[h\]' has a unit that is not a time unit"):
        read_recording(_table([["Time [h]", *(f"b{b}@{a:g}" for b, a in LAYOUT)]], np.column_stack([t, data.T])),
                       filename="x.csv")


def test_a_bad_first_data_row_is_not_taken_for_the_column_names():
    body = b"b1@45,b1@135\n1,oops\n" + b"".join(f"{k},{-k}\n".encode() for k in range(50))
    with pytest.raises(ValueError, match=r"neither names nor numbers \(\['1', 'oops'\]"):
        read_recording(body, filename="x.csv", options=ReadOptions(sample_rate_hz=1000))


def test_units_in_column_names_and_mixed_units_refused(reference):
    rec, data = reference
    t = np.arange(data.shape[1]) / rec.sample_rate_hz
    names = [f"P{k} [mil]" for k in range(8)]
    body = _table([["Time (s)", *names]], np.column_stack([t, data.T / 25.4]))
    chans = parse_channel_map(";".join(f"P{k}=b{b}@{a:g}" for k, (b, a) in enumerate(LAYOUT)))
    got = read_recording(body, filename="x.csv", options=ReadOptions(channels=chans)).recording
    np.testing.assert_allclose(got.channels[3].data_um, data[3], atol=1e-5)
    names[5] = "P5 [mm]"
    body = _table([["Time (s)", *names]], np.column_stack([t, data.T / 25.4]))
    with pytest.raises(ValueError, match=r"probe columns are in different units \(.*'P5 \[mm\]': mm"):
        read_recording(body, filename="x.csv", options=ReadOptions(channels=chans))


def test_volts_read_as_a_wrong_scale_name_what_was_declared(reference):
    """A units check on a recording declared in V names V and the sensitivity, never 'um' (issue 45)."""
    rec, data = reference
    volts = GAP_V + data * 1e-3 * 7.87
    t = np.arange(data.shape[1]) / rec.sample_rate_hz
    body = _table([["Time (s)", *(f"b{b}@{a:g}" for b, a in LAYOUT)]], np.column_stack([t, volts.T]))
    # 7.87 mV/mm instead of 7.87 V/mm: every length 1000x too large
    got = read_recording(body, filename="x.csv", options=ReadOptions(
        units="V", sensitivity_v_per_mm="7.87 mV/mm", gap_voltage_v=GAP_V, clearance_um=150.0)).recording
    declared = [f.values["units"] for f in extract_features(got).sanity if "units" in f.values]
    assert declared                                       # the findings that name the declared units
    assert all(u == "V at 0.00787 V/mm, gap -10 V" for u in declared)


# --------------------------------------------------------------------------- CLI and HTTP: the same verdict


@pytest.fixture(scope="module")
def registry(tmp_path_factory):
    return shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))


def _cli_json(registry, *args):
    res = CliRunner().invoke(cli_app, ["diagnose", *map(str, args), "--registry", str(registry), "--json"])
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout)


def _same_verdict(a, b):
    assert (a["status"], a["severity"], a.get("model_severity")) == (b["status"], b["severity"], b.get("model_severity"))
    assert a["misalignment"] == pytest.approx(b["misalignment"], abs=2e-3)
    for k, p in a["probabilities"].items():
        assert p == pytest.approx(b["probabilities"][k], abs=2e-3)


def test_cli_gives_each_export_the_verdict_of_the_um_file(registry, exports):
    ref = _cli_json(registry, example_path("whirl.csv"), "--channels", LAYOUT_TEXT, "--units", "um")
    for key, (path, channel_map, stated) in exports.items():
        extra = [x for k, v in stated.items() for x in (f"--{k.replace('_', '-')}", v)]
        got = _cli_json(registry, path, "--channels", channel_map, *extra)
        _same_verdict(got, ref)
        assert got["notes"], key


def test_http_gives_each_export_the_verdict_of_the_um_file(tmp_path, registry, exports):
    app = create_app(make_settings(tmp_path, shipped_registry_dir=registry))
    with TestClient(app) as c:
        bearings = ",".join(str(b) for b, _ in LAYOUT)
        angles = ",".join(f"{a:g}" for _, a in LAYOUT)
        r = c.post("/diagnose", params={"units": "um", "bearings": bearings, "angles_deg": angles},
                   files={"file": ("whirl.csv", example_path("whirl.csv").read_bytes())})
        assert r.status_code == 200, r.text
        ref = r.json()
        for key, (path, channel_map, stated) in exports.items():
            r = c.post("/diagnose", params={"channel_map": channel_map, **stated},
                       files={"file": (path.name, path.read_bytes())})
            assert r.status_code == 200, (key, r.text)
            _same_verdict(r.json(), ref)
            notes = r.json()["input_notes"]
            if key == "daq_csv_ms_unit_row":
                assert "column(s) ['BRG 2 TEMP'] are neither time, keyphasor nor in the channel mapping: not read" \
                    in notes
        # the mapping and a file-order layout together, a mapping without '=', a column the file lacks: 422
        path, channel_map, stated = exports["daq_csv_ms_unit_row"]
        for params, needle in (({"channel_map": channel_map, "bearings": "1,1"}, "give the layout one way"),
                               ({"channel_map": "1@45,1@135"}, "COLUMN=b<bearing>@<angle>"),
                               ({"channel_map": "GEN XX=b2@45", **stated}, "'GEN XX' is not a channel name"),
                               ({"channel_map": channel_map, "units": "mV"}, "give the probe sensitivity")):
            r = c.post("/diagnose", params=params, files={"file": (path.name, path.read_bytes())})
            assert r.status_code == 422, (params, r.text)
            assert needle in str(r.json()["detail"]), r.text


# --------------------------------------------------------------------------- an asset's probes, set up once


def test_an_assets_probe_configuration_is_used_by_every_upload_and_said_so(tmp_path, registry, exports):
    from tests.service_util import auth

    path, channel_map, stated = exports["daq_csv_ms_unit_row"]
    body = {"file": (path.name, path.read_bytes())}
    app = create_app(make_settings(tmp_path, shipped_registry_dir=registry))
    with TestClient(app) as c:
        assert c.get("/assets/unit-3/probes").status_code == 404
        # refused as every upload would be: a mapping without '=', an unknown unit, a sensitivity without units
        for bad, needle in (({"channel_map": "1@45,1@135"}, "COLUMN=b<bearing>@<angle>"),
                            ({"units": "inch"}, "units 'inch'"), ({"sensitivity": "200 mV"}, "probe sensitivity"),
                            ({"bearings": "1,1", "angles_deg": "45"}, "1 values for 2 bearings"),
                            ({"rotation": "clockwise"}, "rotation")):
            r = c.put("/assets/unit-3/probes", json=bad, headers=auth())
            assert r.status_code == 422, (bad, r.text)
            assert needle in str(r.json()["detail"]), r.text
        assert c.put("/assets/unit-3/probes", json={"units": "mV"}).status_code == 401          # needs the key
        config = {"channel_map": channel_map, "units": "mV", "sensitivity": DAQ_SENSITIVITY, "gap_voltage_v": GAP_V}
        r = c.put("/assets/unit-3/probes", json=config, headers=auth())
        assert r.status_code == 200, r.text
        assert r.json()["probes"] == config
        assert c.get("/assets/unit-3/probes").json()["probes"] == config
        # the export alone, named to the asset: read with the stored configuration, as if given with it
        r = c.post("/diagnose", params={"asset_id": "unit-3"}, files=body)
        assert r.status_code == 200, r.text
        stored = r.json()
        given = c.post("/diagnose", params={"channel_map": channel_map, **stated, "units": "mV"}, files=body).json()
        _same_verdict(stored, given)
        assert stored["asset_probes"] == {"asset_id": "unit-3", "used": config, "overridden_by_upload": []}
        assert stored["input_notes"][0].startswith("read with asset 'unit-3''s probe configuration: channel_map=")
        # without the asset (or another asset) nothing is assumed: the export's columns are refused by name
        r = c.post("/diagnose", params={"asset_id": "unit-4"}, files=body)
        assert r.status_code == 422 and "are neither a time column" in r.json()["detail"]
        # an upload's own parameters win, group by group: the wrong sensitivity given makes every length 2x
        r = c.post("/diagnose", params={"asset_id": "unit-3", "sensitivity": "100 mV/mil"}, files=body)
        assert r.status_code == 200, r.text
        assert r.json()["asset_probes"]["overridden_by_upload"] == ["sensitivity"]
        assert "sensitivity" not in r.json()["asset_probes"]["used"]
        b2 = {b["bearing"]: b for b in r.json()["bearings"]}[2]["features"]
        b2_ref = {b["bearing"]: b for b in stored["bearings"]}[2]["features"]
        key = next(k for k in b2_ref if k.endswith("_um_pp") and b2_ref[k])
        assert b2[key] == pytest.approx(2 * b2_ref[key], rel=1e-3)
        # the page's plots are read the same way
        r = c.post("/ui/plot-data", params={"asset_id": "unit-3"}, files=body)
        assert r.status_code == 200, r.text
        # removed: the asset's uploads are read as sent again
        assert c.delete("/assets/unit-3/probes", headers=auth()).status_code == 204
        assert c.get("/assets/unit-3/probes").status_code == 404
        r = c.post("/diagnose", params={"asset_id": "unit-3"}, files=body)
        assert r.status_code == 422 and "are neither a time column" in r.json()["detail"]


@pytest.mark.parametrize(("key", "when"), [("labview_lvm", "2026-11-28T04:10:03.123456"),
                                           ("collector_metadata_block", "2026-11-28T04:10:03"),
                                           ("daq_csv_ms_unit_row", None)])
def test_the_recording_time_is_read_from_the_exports_header(exports, key, when):
    """A LabVIEW .lvm header's Date and Time lines, a collector's 'Date:' line; the DAQ CSV carries none."""
    path, cmap, stated = exports[key]
    res = read_recording(path, options=ReadOptions(channels=parse_channel_map(cmap),
                                                   sensitivity_v_per_mm=stated.get("sensitivity"),
                                                   gap_voltage_v=stated.get("gap_voltage_v")))
    assert res.recording.recorded_at == when
    assert any("recorded at" in n for n in res.notes) == (when is not None)


@pytest.mark.parametrize(("text", "iso"), [
    ("2026/03/02 10:00:00.5", "2026-03-02T10:00:00.500000"), ("02.03.2026 10:00", "2026-03-02T10:00:00"),
    ("02-Mar-26 10:00:00", "2026-03-02T10:00:00"), ("2026-03-02T10:00:00Z", "2026-03-02T10:00:00+00:00"),
    ("OCT run 7", None), ("", None)])
def test_recording_time_spellings(text, iso):
    from rotordiag.features.reader import parse_recorded_at

    assert parse_recorded_at(text) == iso


def test_hdf5_and_uff_recording_times(tmp_path, reference):
    """An HDF5 file's ``recorded_at`` attribute and the UFF 58 records' ID line 3 give the recording time."""
    import h5py
    import pyuff

    rec, data = reference
    h5 = tmp_path / "r.h5"
    with h5py.File(h5, "w") as f:
        f.create_dataset("waveforms", data=data)
        f.attrs["sample_rate_hz"] = rec.sample_rate_hz
        f.attrs["recorded_at"] = "2025-01-14T08:30:00Z"
    assert read_recording(h5).recording.recorded_at == "2025-01-14T08:30:00+00:00"
    uff = tmp_path / "r.uff"
    sets = [{"type": 58, "func_type": 1, "rsp_node": 1, "rsp_dir": 1, "ref_dir": 1, "ref_node": 1,
             "data": data[k].astype(float), "x": np.arange(data.shape[1]) / rec.sample_rate_hz,
             "id1": f"b{b}@{a:g}", "id2": "", "id3": "14-Jan-25 08:30:00", "id4": "", "id5": "",
             "rsp_ent_name": "probe", "ref_ent_name": "probe", "abscissa_spacing": 1,
             "abscissa_spec_data_type": 17, "ordinate_spec_data_type": 8, "ordinate_axis_units_lab": "um",
             "orddenom_spec_data_type": 13, "z_axis_spec_data_type": 0}
            for k, (b, a) in enumerate(LAYOUT)]
    pyuff.UFF(str(uff)).write_sets(sets, mode="overwrite")
    assert read_recording(uff).recording.recorded_at == "2025-01-14T08:30:00"


def test_an_uploads_recording_time_from_its_file_orders_the_trend(tmp_path, registry, exports):
    """The LabVIEW export's header time becomes the stored recording time (said in input_notes); a given
    recorded_at wins; an anonymous upload is answered without storing."""
    from tests.service_util import auth

    path, channel_map, stated = exports["labview_lvm"]
    app = create_app(make_settings(tmp_path, shipped_registry_dir=registry))
    with TestClient(app) as c:
        params = {"channel_map": channel_map, **stated, "asset_id": "unit-lvm"}
        r = c.post("/diagnose", params=params, files={"file": (path.name, path.read_bytes())}, headers=auth())
        assert r.status_code == 200, r.text
        assert "recording time 2026-11-28 04:10 UTC from the file (give recorded_at to override it)" \
            in r.json()["input_notes"]
        r = c.post("/diagnose", params={**params, "recorded_at": "2025-06-01T12:00:00Z"},
                   files={"file": (path.name, path.read_bytes())}, headers=auth())
        assert r.status_code == 200 and not any("from the file" in n for n in r.json()["input_notes"])
        pts = c.get("/assets/unit-lvm/history").json()["points"]
        assert [p["trend_time"][:16] for p in pts] == ["2025-06-01T12:00", "2026-11-28T04:10"]


def test_an_asset_also_keeps_its_rotation_clearance_speed_band_and_model(tmp_path, registry, exports):
    """Set up once: the asset's rotation, clearance, speed band and model version are used by every upload (the
    answer says so), and an upload's own value wins for its group; a version not registered is a 4xx."""
    from tests.service_util import auth

    path, channel_map, stated = exports["daq_csv_ms_unit_row"]
    body = {"file": (path.name, path.read_bytes())}
    app = create_app(make_settings(tmp_path, shipped_registry_dir=registry))
    with TestClient(app) as c:
        version = c.get("/models").json()["versions"][0]["version"]
        config = {"channel_map": channel_map, "units": "mV", "sensitivity": stated["sensitivity"],
                  "gap_voltage_v": stated["gap_voltage_v"], "rotation": "ccw", "viewed_from": "driver",
                  "clearance_um": 350.0, "speed_range_rpm": "1750,1850", "model_version": version}
        r = c.put("/assets/unit-9/probes", json=config, headers=auth())
        assert r.status_code == 200, r.text
        v = c.post("/diagnose", params={"asset_id": "unit-9"}, files=body).json()
        assert v["asset_probes"]["used"] == config and v["model_version"] == version
        assert v["offset_um"] is not None                  # the stored clearance turned Δ into µm
        assert 1750 <= v["speed_rpm"] <= 1850
        v = c.post("/diagnose", params={"asset_id": "unit-9", "clearance_um": 175.0}, files=body).json()
        assert v["asset_probes"]["overridden_by_upload"] == ["clearance"]
        r = c.put("/assets/unit-9/probes", json={**config, "clearance_um": -3}, headers=auth())
        assert r.status_code == 422
        r = c.put("/assets/unit-9/probes", json={**config, "model_version": "v9999"}, headers=auth())
        assert r.status_code == 404 and "GET /models" in r.json()["detail"]
