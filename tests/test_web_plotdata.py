"""The web page's server side through the TestClient: the page and its static files, and
``POST /ui/plot-data`` against signals whose orbits and spectra are known in closed form."""
from __future__ import annotations

import io
import re

import numpy as np
import pytest
from fastapi.testclient import TestClient

from rotordiag.service.plotdata import _reduce_max, full_spectrum_um_pp, half_spectrum_um_pp
from tests.service_util import make_settings

FS = 2048.0
F1 = 32.0                 # 1920 r/min: 64 samples per revolution, lines on FFT bins
N = 2048                  # 32 revolutions
R1, A2, PHI2, AW = 10.0, 3.0, 0.5, 2.0      # 1X forward circle, 2X forward circle, oil-whirl-band line (0.45X)


def _xy(t):
    th = 2 * np.pi * F1 * t
    x = R1 * np.cos(th) + A2 * np.cos(2 * th + PHI2) + AW * np.cos(0.45 * th) + 40.0   # + a DC gap
    y = R1 * np.sin(th) + A2 * np.sin(2 * th + PHI2) + AW * np.sin(0.45 * th) - 25.0
    return x, y


def _probes(angles_deg=(45.0, 135.0), scale=1.0):
    t = np.arange(N) / FS
    x, y = _xy(t)
    a = np.deg2rad(angles_deg)
    return np.vstack([np.cos(ai) * x + np.sin(ai) * y for ai in a]) * scale


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    from rotordiag.service.main import create_app

    with TestClient(create_app(make_settings(tmp_path_factory.mktemp("webapi")))) as c:
        yield c


def _csv(arr):
    buf = io.StringIO()
    np.savetxt(buf, arr.T, delimiter=",", fmt="%.9f")
    return buf.getvalue()


def _post_csv(client, arr, **params):
    params = {"sample_rate_hz": FS, "bearings": "2,2", "speed_rpm": 60 * F1, **params}
    return client.post("/ui/plot-data", params=params, files={"file": ("rec.csv", _csv(arr), "text/csv")})


# --- the page ---------------------------------------------------------------------------------------

def test_page_and_static_files_are_served_self_contained(client):
    r = client.get("/")
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
    csp = r.headers["content-security-policy"]
    assert "default-src 'self'" in csp and "script-src 'self'" in csp
    html = r.text
    assert '<script src="/ui/static/app.js"' in html and 'href="/ui/static/style.css"' in html
    js = client.get("/ui/static/app.js")
    css = client.get("/ui/static/style.css")
    assert js.status_code == 200 and js.headers["content-type"].startswith("text/javascript")
    assert css.status_code == 200 and css.headers["content-type"].startswith("text/css")
    for text in (html, js.text, css.text):          # nothing fetched from another host, no CDN
        assert not re.search(r"(https?:)?//[a-z0-9.-]+\.[a-z]{2,}", text, re.I)
    assert "@import" not in css.text and "url(" not in css.text
    assert client.get("/ui/static/main.py").status_code == 404
    assert client.get("/ui/static/index.html").status_code == 404
    # the page's routes stay out of the API schema
    paths = client.get("/openapi.json").json()["paths"]
    assert "/" not in paths and "/ui/plot-data" not in paths


def test_every_form_control_has_a_label(client):
    html = client.get("/").text
    ids = re.findall(r'<(?:input|select|textarea)[^>]*\bid="([^"]+)"', html)
    labelled = set(re.findall(r'<label for="([^"]+)"', html))
    wrapped = set(re.findall(r'<label><input[^>]*\bid="([^"]+)"', html))
    assert ids and not [i for i in ids if i not in labelled | wrapped]


# --- plot data: known answers ---------------------------------------------------------------------------

def test_spectra_read_the_known_line_amplitudes(client):
    r = _post_csv(client, _probes())
    assert r.status_code == 200, r.text
    d = r.json()
    assert d["speed_rpm"] == pytest.approx(60 * F1) and d["speed_source"] == "given" and d["n_revs"] == 32
    assert d["whirl_band_orders"] == [0.38, 0.49]
    (b,) = d["bearings"]
    assert b["bearing"] == 2 and b["probe_angles_deg"] == [45.0, 135.0]
    hs = b["half_spectrum"]
    f, a = np.array(hs["freq_hz"]), np.array(hs["amp_um_pp"])
    assert f[-1] <= 4.5 * F1 and f[-1] > 4.4 * F1
    # each probe sees the 1X and 2X circles as lines of their radius: 2r peak-to-peak
    for order, radius in ((1, R1), (2, A2)):
        k = int(np.argmin(abs(f - order * F1)))
        assert a[:, k] == pytest.approx([2 * radius, 2 * radius], rel=1e-3)
    # the 0.45X line falls between bins: within the Hann window's scalloping loss (≤ 15 %)
    k = int(np.argmin(abs(f - 0.45 * F1)))
    assert 0.85 * 2 * AW <= a[0, k] <= 2 * AW
    fs_ = b["full_spectrum"]
    f, a = np.array(fs_["freq_hz"]), np.array(fs_["amp_um_pp"])
    assert np.all(np.diff(f) > 0) and f[0] < 0 < f[-1]
    at = lambda hz: a[int(np.argmin(abs(f - hz)))]  # noqa: E731
    assert at(F1) == pytest.approx(2 * R1, rel=1e-3) and at(2 * F1) == pytest.approx(2 * A2, rel=1e-3)
    assert at(-F1) < 1e-3 and at(-2 * F1) < 1e-3           # forward circles: nothing at negative frequencies


def test_orbits_filtered_raw_and_once_per_rev_marks(client):
    d = _post_csv(client, _probes()).json()
    o = d["bearings"][0]["orbit"]
    th = np.linspace(0, 2 * np.pi, len(o["filtered"]["1x"]["x_um"]))
    np.testing.assert_allclose(o["filtered"]["1x"]["x_um"], R1 * np.cos(th), atol=1e-3 * R1)
    np.testing.assert_allclose(o["filtered"]["1x"]["y_um"], R1 * np.sin(th), atol=1e-3 * R1)
    np.testing.assert_allclose(o["filtered"]["2x"]["x_um"], A2 * np.cos(2 * th + PHI2), atol=2e-3 * R1)
    np.testing.assert_allclose(o["filtered"]["1x2x"]["y_um"], R1 * np.sin(th) + A2 * np.sin(2 * th + PHI2),
                               atol=2e-3 * R1)
    # raw: the last 8 revolutions, mean removed; marks: the signal at θ = 2πm, same offset
    assert o["revs"] == 8 and len(o["raw_x_um"]) == 8 * 64
    mx, my = d["bearings"][0]["mean_um"]
    t = np.arange(N - 8 * 64, N) / FS
    x, y = _xy(t)
    np.testing.assert_allclose(np.array(o["raw_x_um"]) + mx, x, atol=1e-6)
    np.testing.assert_allclose(np.array(o["raw_y_um"]) + my, y, atol=1e-6)
    xm, ym = _xy(np.arange(24, 32) / F1)
    np.testing.assert_allclose(np.array(o["raw_marks_um"]) + [mx, my], np.column_stack([xm, ym]), atol=1e-6)
    assert mx == pytest.approx(40.0, abs=0.3) and my == pytest.approx(-25.0, abs=0.3)


def test_units_and_keyphasor_phase_reference(client):
    # the same signals in mm give the same µm pictures
    um = _post_csv(client, _probes()).json()["bearings"][0]
    mm = _post_csv(client, _probes(scale=1e-3), units="mm").json()["bearings"][0]
    np.testing.assert_allclose(mm["half_spectrum"]["amp_um_pp"], um["half_spectrum"]["amp_um_pp"], rtol=1e-6, atol=1e-5)
    # keyphasor pulses a quarter revolution late: θ = 0 where the 1X circle is at (0, R1)
    kp = (np.arange(0, 31) + 0.25) / F1
    body = {"sample_rate_hz": FS, "keyphasor_times_s": kp.tolist(),
            "channels": [{"bearing": 3, "angle_deg": a, "units": "um", "data": p.tolist()}
                         for a, p in zip((45.0, 135.0), _probes())]}
    r = client.post("/ui/plot-data", json=body)
    assert r.status_code == 200, r.text
    d = r.json()
    assert d["phase_reference"] == "keyphasor" and d["speed_rpm"] == pytest.approx(60 * F1, rel=1e-9)
    f1x = d["bearings"][0]["orbit"]["filtered"]["1x"]
    assert (f1x["x_um"][0], f1x["y_um"][0]) == (pytest.approx(0.0, abs=2e-2), pytest.approx(R1, rel=2e-3))


def test_a_keyphasor_per_take(client):
    """Bearings 2 and 3 in two takes, the second 0.3 revolution later on its own clock, each with its keyphasor:
    each bearing's pictures are cut and phased by its take's pulses, so both filtered 1X orbits start at the mark."""
    late = int(round(0.3 / F1 * FS))
    second = np.vstack([np.cos(np.deg2rad(a)) * x + np.sin(np.deg2rad(a)) * y for a in (45.0, 135.0)
                        for x, y in [_xy((np.arange(N) + late) / FS)]])
    first_kp = (np.arange(0, 31) + 0.25) / F1
    second_kp = first_kp[first_kp >= late / FS] - late / FS
    body = {"sample_rate_hz": FS, "keyphasor_times_s": [first_kp.tolist(), second_kp.tolist()],
            "acquisitions": "2;3",
            "channels": [{"bearing": b, "angle_deg": a, "units": "um", "data": p.tolist()}
                         for b, probes in ((2, _probes()), (3, second)) for a, p in zip((45.0, 135.0), probes)]}
    r = client.post("/ui/plot-data", json=body)
    assert r.status_code == 200, r.text
    d = r.json()
    assert d["phase_reference"] == "keyphasor" and [b["bearing"] for b in d["bearings"]] == [2, 3]
    for b in d["bearings"]:
        f1x = b["orbit"]["filtered"]["1x"]
        assert (f1x["x_um"][0], f1x["y_um"][0]) == (pytest.approx(0.0, abs=2e-2), pytest.approx(R1, rel=2e-3))
        assert len(b["orbit"]["raw_x_um"]) == 8 * 64


def test_hdf5_and_npy_uploads(client):
    import h5py

    buf = io.BytesIO()
    with h5py.File(buf, "w") as f:
        ds = f.create_dataset("waveforms", data=_probes())
        ds.attrs["sample_rate_hz"] = FS
        f["channels/bearing"] = np.array([4, 4])
        f["channels/angle_deg"] = np.array([45.0, 135.0])
    r = client.post("/ui/plot-data", params={"speed_rpm": 60 * F1},
                    files={"file": ("rec.h5", buf.getvalue(), "application/x-hdf5")})
    assert r.status_code == 200, r.text
    assert r.json()["bearings"][0]["bearing"] == 4
    npy = io.BytesIO()
    np.save(npy, _probes().astype(np.float32))
    r = client.post("/ui/plot-data", params={"sample_rate_hz": FS, "bearings": "1,1"}, content=npy.getvalue(),
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 200, r.text
    # the speed estimated from the signals when none is given
    assert r.json()["speed_source"] == "estimated" and r.json()["speed_rpm"] == pytest.approx(60 * F1, rel=1e-3)


@pytest.mark.parametrize("case,status,needle", [
    ("text in csv", 422, "CSV file"),
    ("no sample rate", 422, "sample_rate_hz"),
    ("too short", 422, "revolutions"),
    ("one probe", 422, "bearing"),
    ("content type", 415, "Content-Type"),
    ("bad angles", 422, "angles_deg"),
])
def test_bad_recordings_get_a_message_not_a_5xx(client, case, status, needle):
    if case == "text in csv":
        r = client.post("/ui/plot-data", params={"sample_rate_hz": FS, "bearings": "2,2"},
                        files={"file": ("x.csv", "1.0,2.0\n3.0,oops\n", "text/csv")})
    elif case == "no sample rate":
        r = client.post("/ui/plot-data", params={"bearings": "2,2"}, files={"file": ("x.csv", _csv(_probes()), "text/csv")})
    elif case == "too short":
        r = _post_csv(client, _probes()[:, :200])
    elif case == "one probe":
        r = _post_csv(client, _probes()[:1], bearings="2")
    elif case == "content type":
        r = client.post("/ui/plot-data", content=b"hello", headers={"Content-Type": "text/plain"})
    else:
        r = _post_csv(client, _probes(), angles_deg="45,abc")
    assert r.status_code == status, r.text
    detail = r.json()["detail"]
    assert needle in (detail if isinstance(detail, str) else str(detail)), detail


@pytest.mark.parametrize("path", ["/ui/plot-data", "/ui/transient-plots"])
@pytest.mark.parametrize("asset_id, needle", [("..", "may not be '.' or '..'"), ("unit 3", "only letters, digits"),
                                               ("", "at least 1 character")])
def test_the_pages_asset_id_is_checked_as_diagnose_checks_it(client, path, asset_id, needle):
    """The page's uploads take /diagnose's asset identifier (``schemas.AssetId``): a 422 saying what to change."""
    r = _post_csv(client, _probes(), asset_id=asset_id) if path == "/ui/plot-data" else \
        client.post(path, params={"sample_rate_hz": FS, "bearings": "2,2", "asset_id": asset_id},
                    files={"file": ("rec.csv", _csv(_probes()), "text/csv")})
    assert r.status_code == 422, r.text
    assert needle in str(r.json()["detail"]), r.json()


# --- helpers ------------------------------------------------------------------------------------------

def test_spectrum_helpers_and_bin_reduction():
    t = np.arange(4096) / 4096.0
    f, a = half_spectrum_um_pp(np.vstack([3.0 * np.cos(2 * np.pi * 100 * t)]), 4096.0, 500.0)
    assert a[0, np.argmin(abs(f - 100))] == pytest.approx(6.0, rel=1e-9)
    f, a = full_spectrum_um_pp(2 * np.cos(2 * np.pi * 50 * t), -2 * np.sin(2 * np.pi * 50 * t), 4096.0, 500.0)
    assert a[np.argmin(abs(f + 50))] == pytest.approx(4.0, rel=1e-9)     # a reverse circle of radius 2
    assert a[np.argmin(abs(f - 50))] < 1e-9
    freq = np.arange(10_000, dtype=float)
    amps = np.zeros((2, freq.size))
    amps[0, 1234], amps[1, 8765] = 5.0, 7.0
    fr, ar = _reduce_max(freq, amps, 4096)
    assert fr.size <= 4096 and 1234.0 in fr and 8765.0 in fr and ar.max(axis=1).tolist() == [5.0, 7.0]


def test_pictures_are_drawn_at_the_verdicts_speed(client, monkeypatch):
    """When the verdict's speed is not the features package's estimate (models.checks.speed_choice chose another
    reading of a doubtful estimate), the page's pictures mark the orders at the verdict's speed."""
    import rotordiag.models.checks.speed_choice as sc
    import rotordiag.models.pipeline as pl
    from rotordiag.features import extract_features

    from .test_features_speed import _whip_recording

    rec = _whip_recording(3075.0, 20.5, one_x_um=0.08, comb_um=0.0, noise_um=0.3)
    assert extract_features(rec).speed_rpm == pytest.approx(1230.0, rel=5e-3)
    chosen = 3074.0

    def choose(recording, fr, ood_score, ood, judge):      # stands in for the model's judgement
        return sc.SpeedChoice(fr.speed_rpm, 2.0, ((chosen, 0.5, False),), chosen, 0.5)

    monkeypatch.setattr(pl, "choose_speed", choose)
    body = {"sample_rate_hz": rec.sample_rate_hz,
            "channels": [{"bearing": c.bearing, "angle_deg": c.angle_deg, "units": c.units, "data": c.data.tolist()}
                         for c in rec.channels]}
    verdict = client.post("/diagnose", json=body)
    plots = client.post("/ui/plot-data", json=body)
    assert verdict.status_code == 200 and plots.status_code == 200, (verdict.text[:300], plots.text[:300])
    assert verdict.json()["speed_rpm"] == pytest.approx(chosen) and plots.json()["speed_rpm"] == pytest.approx(chosen)
    assert plots.json()["speed_source"] == "estimated"
