"""The web page end to end: a real `rotordiag serve` on 127.0.0.1 driven by headless Chromium (Selenium).

Debian's ``chromium`` + ``chromium-driver`` are required (``.ci/run`` installs them); without them these
tests fail with a message saying what to install — they are never skipped. Screenshots go to
``test-artifacts/web/`` (git-ignored).
"""
from __future__ import annotations

import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from rotordiag.core.timefmt import readable_time
from tests.service_util import probe_signals_um, two_takes, write_takes_csv

ROOT = Path(__file__).resolve().parent.parent
ARTIFACTS = ROOT / "test-artifacts" / "web"
CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
FS_HZ = 2048.0
SPEED_RPM = 1800.0
CLEARANCE_UM = 350.0
#: the page's colours (service/web/static/app.js COLORS) whose pixels prove a trace was drawn
BLUE_1X = (0x1F, 0x5F, 0xA8)
VIOLET_FULL = (0x5F, 0x3D, 0xC4)
#: the trend plot's bearing 1-4 colours (app.js COLORS.bearing)
BEARING_COLOURS = ((0x1F, 0x5F, 0xA8), (0xD9, 0x48, 0x0F), (0x2B, 0x8A, 0x3E), (0x86, 0x2E, 0x9C))
#: the severity band colours of the trend plot, as drawn at 13 % opacity on white
GREEN_ALIGNED = (0x2E, 0x7D, 0x32)


# --- recordings ------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def recordings():
    """Three simulated recordings of the default plant (Δ = 0.05, 0.2, 0.45): (n_points, 8) µm, probes at
    45° / 135° on bearings 1-4 (the service's default layout for 8 channels)."""
    from rotordiag.simulator import Plant, simulate

    out = {}
    for delta in (0.05, 0.2, 0.45):
        res = simulate(Plant.default(), SPEED_RPM, delta, 0.05, mechanism="rigid", transient_revs=100,
                       record_revs=34, sample_rate_hz=FS_HZ)
        assert res.status == "ok", res.status
        chans = probe_signals_um(res.journal_displacements_m)
        out[delta] = np.column_stack([d for _, _, d in chans])
    return out


def _write_csv(path: Path, data: np.ndarray) -> Path:
    header = ",".join(f"b{b}_{a:g}deg_um" for b in (1, 2, 3, 4) for a in (45, 135))
    np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.6f")
    return path


def _write_npy(path: Path, data: np.ndarray) -> Path:
    np.save(path, data.T.astype(np.float32))
    return path


def _write_hdf5(path: Path, data: np.ndarray) -> Path:
    import h5py

    with h5py.File(path, "w") as f:
        ds = f.create_dataset("waveforms", data=data.T)
        ds.attrs["sample_rate_hz"] = FS_HZ
        ds.attrs["units"] = "um"
        f["channels/bearing"] = np.repeat([1, 2, 3, 4], 2)
        f["channels/angle_deg"] = np.tile([45.0, 135.0], 4)
    return path


def _json_body(data: np.ndarray) -> dict:
    layout = [(b, a) for b in (1, 2, 3, 4) for a in (45.0, 135.0)]
    return {"channels": [{"bearing": b, "angle_deg": a, "units": "um", "data": [round(float(v), 5) for v in data[:, i]]}
                         for i, (b, a) in enumerate(layout)]}


# --- server and browser ----------------------------------------------------------------------------

def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _get(url: str):
    try:
        with urllib.request.urlopen(url, timeout=60) as r:
            return r.status, json.loads(r.read() or b"null")
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read() or b"null")


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    from rotordiag.service.core.config import SHIPPED_REGISTRY_DIR
    from tests.service_util import shipped_or_tiny_registry

    tmp = tmp_path_factory.mktemp("web")
    env = dict(os.environ, ROTORDIAG_DATA_DIR=str(tmp / "data"), ROTORDIAG_API_KEY="web-test-key",
               ROTORDIAG_ENVIRONMENT="development", ROTORDIAG_LOG_LEVEL="warning")
    if not (SHIPPED_REGISTRY_DIR / "active").is_file():   # no default model shipped yet: a tiny one
        shutil.copytree(shipped_or_tiny_registry(), tmp / "registry")
        env["ROTORDIAG_MODEL_REGISTRY_DIR"] = str(tmp / "registry")
    port = _free_port()
    exe = Path(sys.executable).parent / "rotordiag"
    proc = subprocess.Popen([str(exe), "serve", "--host", "127.0.0.1", "--port", str(port)], cwd=tmp, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    base = f"http://127.0.0.1:{port}"
    t0 = time.monotonic()
    while True:
        if proc.poll() is not None:
            pytest.fail(f"server exited with {proc.returncode}:\n{proc.stdout.read()}")
        try:
            if _get(base + "/health")[0] == 200:
                break
        except OSError:
            pass
        if time.monotonic() - t0 > 90:
            proc.kill()
            pytest.fail(f"server did not become healthy within 90 s:\n{proc.communicate()[0]}")
        time.sleep(0.25)
    REGISTRIES[base] = Path(env.get("ROTORDIAG_MODEL_REGISTRY_DIR") or tmp / "data" / "registry")
    yield base
    proc.send_signal(signal.SIGINT)
    try:
        out, _ = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, _ = proc.communicate()
    assert "Traceback" not in out, out


#: the registry directory of each test server (by its base URL)
REGISTRIES: dict[str, Path] = {}


@pytest.fixture(scope="module")
def browser():
    missing = [p for p in (CHROMIUM, CHROMEDRIVER) if not Path(p).is_file()]
    if missing:
        pytest.fail(f"{', '.join(missing)} not found: the web page's browser tests need Debian's chromium and "
                    "chromium-driver (`apt-get install chromium chromium-driver`; .ci/run installs them)")
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        pytest.fail("selenium is not installed: `pip install -e '.[dev]'`")
    os.environ["SE_OFFLINE"] = "true"   # Selenium Manager must never download a browser or driver
    profile = tempfile.mkdtemp(prefix="rotordiag-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--disable-dev-shm-usage", "--force-device-scale-factor=1", "--window-size=1366,900",
                 f"--user-data-dir={profile}"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(executable_path=CHROMEDRIVER), options=opts)
    driver.set_page_load_timeout(60)
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    yield driver
    driver.quit()
    shutil.rmtree(profile, ignore_errors=True)


def _wait(driver, predicate, timeout=180, what="condition"):
    from selenium.common.exceptions import NoSuchElementException, StaleElementReferenceException

    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        try:
            value = predicate(driver)
        except (StaleElementReferenceException, NoSuchElementException):
            value = None                    # the page re-rendered the element between finding and reading it
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}; page state "
                         f"{driver.execute_script('return document.body.dataset.state')!r}, error "
                         f"{driver.find_element('id', 'form-error').text!r}")


def Select(element):
    """selenium's Select (imported here: the module fails with a clear message when selenium is missing)."""
    from selenium.webdriver.support.select import Select as _Select

    return _Select(element)


def _open(driver, base, width=1366, height=900):
    driver.set_window_size(width, height)
    driver.get(base + "/")
    _wait(driver, lambda d: d.execute_script("return document.body.dataset.state") == "idle", 30, "the page script")
    _wait(driver, lambda d: d.find_elements("css selector", "#models-table tbody tr"), 30, "the models table")


def _screenshot(driver, name: str) -> Path:
    """Full-page screenshot (the window is stretched to the page height, then restored)."""
    w, h = driver.get_window_size()["width"], driver.get_window_size()["height"]
    full = driver.execute_script("return document.documentElement.scrollHeight")
    driver.set_window_size(w, max(h, full + 120))
    driver.execute_script("window.scrollTo(0, 0)")
    time.sleep(0.4)                                        # the page redraws its canvases on resize
    path = ARTIFACTS / f"{name}.png"
    driver.save_screenshot(str(path))
    driver.set_window_size(w, h)
    return path


def _submit_file(driver, path: Path | list[Path], *, asset: str = "", sample_rate: str = "", clearance: str = "",
                 key: str = "", expect: str = "done"):
    """Submit ``path`` (a list: several files chosen at once, the takes of one recording) with these fields
    (``key``: the API key typed in the form, without which the diagnosis is not stored)."""
    d = driver
    d.find_element("css selector", "input[name=source][value=file]").click()
    for field, value in (("sample-rate", sample_rate), ("clearance", clearance), ("asset", asset),
                         ("diagnose-key", key)):
        el = d.find_element("id", field)
        el.clear()
        if value:
            el.send_keys(value)
    chooser = d.find_element("id", "file")
    chooser.clear()                          # the input takes several files: chromedriver would add to the last ones
    chooser.send_keys("\n".join(str(p) for p in (path if isinstance(path, list) else [path])))
    d.execute_script("document.body.dataset.state = 'submitted'")
    d.find_element("id", "diagnose-btn").click()
    state = _wait(d, lambda dr: dr.execute_script(
        "const s = document.body.dataset.state; return s === 'done' || s === 'error' ? s : null"), what="the verdict")
    assert state == expect, d.find_element("id", "form-error").text


_PIXELS_JS = """
const c = document.getElementById(arguments[0]);
const colours = arguments[1];
const img = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
let ink = 0, match = 0;
for (let i = 0; i < img.length; i += 4) {
  if (img[i] < 235 || img[i + 1] < 235 || img[i + 2] < 235) ink++;
  if (colours.some((rgb) => Math.abs(img[i] - rgb[0]) < 40 && Math.abs(img[i + 1] - rgb[1]) < 40
                            && Math.abs(img[i + 2] - rgb[2]) < 40)) match++;
}
return {w: c.width, h: c.height, cw: c.clientWidth, ch: c.clientHeight, dpr: window.devicePixelRatio, ink, match};
"""


def _canvas(driver, canvas_id: str, *colours) -> dict:
    """Canvas size and pixel counts: ``ink`` (anything not white), ``match`` (pixels of any of ``colours``)."""
    info = driver.execute_script(_PIXELS_JS, canvas_id, [list(c) for c in colours])
    assert info["w"] == round(info["cw"] * info["dpr"]) and info["h"] == round(info["ch"] * info["dpr"]), info
    return info


def _verdict_api(base: str, data: np.ndarray) -> dict:
    body = {"sample_rate_hz": FS_HZ, "clearance_um": CLEARANCE_UM, **_json_body(data)}
    req = urllib.request.Request(base + "/diagnose", data=json.dumps(body).encode(),
                                 headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=120) as r:
        return json.loads(r.read())


# --- tests -------------------------------------------------------------------------------------------

def test_page_loads_with_models_health_and_labelled_controls(server, browser):
    _open(browser, server)
    status, models = _get(server + "/models")
    assert status == 200
    active = models["active"]
    _wait(browser, lambda d: "active" in d.find_element("css selector", f"#models-table tr[data-version='{active}']").text,
          30, "the active version marked in the table")
    _wait(browser, lambda d: "active model" in d.find_element("id", "health").text, 30, "the health line")
    assert active in browser.find_element("id", "health").text
    unlabelled = browser.execute_script("""
        return [...document.querySelectorAll('input, select, textarea, button')].filter((e) => {
          if (e.type === 'hidden') return false;
          if (e.tagName === 'BUTTON') return !e.textContent.trim() && !e.getAttribute('aria-label');
          const byFor = e.id && document.querySelector(`label[for="${e.id}"]`);
          return !(byFor || e.closest('label') || e.getAttribute('aria-label'));
        }).map((e) => e.id || e.name);""")
    assert unlabelled == []
    # the train and probe-angle figure beside the bearing and angle fields (numbering from the other end and
    # wrong angles are mistakes the checks do not always catch)
    fig = browser.find_element("id", "train-figure")
    assert fig.is_displayed() and fig.size["width"] > 200
    labels = browser.execute_script(
        "return [...document.querySelectorAll('#train-figure svg text')].map((t) => t.textContent)")
    assert {"1", "2", "3", "4", "generator", "exciter", "coupling"} <= set(labels)
    assert "generator far end" in fig.text and "exciter far end" in fig.text
    _screenshot(browser, "form-train-figure")
    # nothing is loaded from anywhere but this server
    origins = browser.execute_script(
        "return performance.getEntriesByType('resource').map((r) => new URL(r.name).origin)")
    assert origins and set(origins) == {server}


def test_inconclusive_verdict_shows_no_severity_only_reasons_and_evidence(server, browser, recordings, tmp_path):
    """An orbit 25× too large for the stated clearance (mils written as µm): the page shows the
    inconclusive status, what to check and the measured evidence — no severity badge, no Δ."""
    data = recordings[0.2]
    _open(browser, server)
    _submit_file(browser, _write_csv(tmp_path / "unit.csv", data * 25.4), sample_rate=str(FS_HZ),
                 clearance=str(CLEARANCE_UM))
    d = browser
    page = d.execute_script("return window.rotordiag.state.verdict")
    assert page["status"] == "inconclusive"
    assert "Inconclusive" in d.find_element("id", "verdict-status").text
    assert not d.find_element("id", "verdict-severity-row").is_displayed()
    assert not d.find_element("id", "verdict-delta-row").is_displayed()
    assert not d.find_element("id", "verdict-probs").is_displayed()
    reasons = [e.text for e in d.find_elements("css selector", "#verdict-reasons li")]
    assert reasons and "clearance" in reasons[0] and "units" in reasons[0]
    assert len(d.find_elements("css selector", "#verdict-evidence tbody tr")) == len(page["evidence"]) > 0


def test_volts_read_as_micrometres_show_what_to_do_and_no_severity(server, browser, recordings, tmp_path):
    """The issue's case: a probe's volts (7.87 V/mm, −10 V gap) sent as µm. The model still has a class, but the
    page opens with the headline "check the measurement first" and shows no severity badge at all."""
    data = recordings[0.2] * 7.87e-3 - 10.0
    _open(browser, server)
    _submit_file(browser, _write_csv(tmp_path / "volts.csv", data), sample_rate=str(FS_HZ))
    d = browser
    v = d.execute_script("return window.rotordiag.state.verdict")
    assert v["headline"]["action"] == "check_measurement" and v["headline"]["show_severity"] is False
    assert v["severity"] != "inconclusive"                    # the model called a class: the page must not show it
    shown = d.find_element("id", "verdict-headline")
    assert shown.is_displayed() and shown.text.startswith("What to do (before acting): check the measurement first")
    assert not d.find_element("id", "verdict-severity-row").is_displayed()
    assert d.find_element("id", "verdict-severity").text == ""
    assert d.find_element("id", "verdict-status").text.startswith("Measurement in doubt: no severity is shown")
    _screenshot(d, "volts_as_um")


def test_a_doubtful_estimated_speed_is_marked_in_doubt(server, browser, tmp_path):
    """No speed given, an oil whip 60 times the 1X: the estimated speed is in doubt (``speed_ambiguous``), and the
    page says so beside the speed, not only in the reasons; the pictures are drawn at the verdict's speed."""
    from tests.test_features_speed import _whip_recording

    rec = _whip_recording(3075.0, 20.5, one_x_um=0.08, comb_um=0.0, noise_um=0.3)
    data = np.column_stack([c.data for c in rec.channels])          # b1@45, b1@135, …, b4@135 as _write_csv names
    _open(browser, server)
    _submit_file(browser, _write_csv(tmp_path / "whip.csv", data), sample_rate=str(rec.sample_rate_hz))
    d = browser
    page = d.execute_script("return window.rotordiag.state")
    assert "speed_ambiguous" in [r["code"] for r in page["verdict"]["reasons"]] and page["verdict"]["status"] != "confident"
    shown = d.find_element("id", "verdict-speed").text
    assert shown.startswith(f"{page['verdict']['speed_rpm']:.1f} r/min") and "estimated" in shown and "in doubt" in shown
    assert page["plots"]["speed_rpm"] == pytest.approx(page["verdict"]["speed_rpm"])
    _screenshot(d, "speed_in_doubt")


def test_csv_upload_shows_verdict_orbits_and_spectra(server, browser, recordings, tmp_path):
    data = recordings[0.2]
    _open(browser, server)
    _submit_file(browser, _write_csv(tmp_path / "unit.csv", data), sample_rate=str(FS_HZ),
                 clearance=str(CLEARANCE_UM))
    d = browser
    page = d.execute_script("return window.rotordiag.state.verdict")
    api = _verdict_api(server, data)                       # the same recording straight to the API
    assert page["severity"] == api["severity"]
    assert page["misalignment"] == pytest.approx(api["misalignment"], rel=1e-6)
    assert d.find_element("id", "verdict-severity").text.lower() == api["severity"]
    assert d.find_element("id", "verdict-delta").text.startswith(f"{api['misalignment']:.3f}")
    for bound in api["misalignment_interval"]:
        if bound is not None:
            assert f"{bound:.3f}" in d.find_element("id", "verdict-delta").text
    assert d.find_element("id", "verdict-offset").text.startswith(f"{api['offset_um']:.1f} µm")
    # the direction row: the answer's text, or why there is none (a model without direction heads says so)
    direction = api["direction"]
    assert d.find_element("id", "verdict-direction").text == (
        direction["text"] if direction["estimated"] else f"not estimated — {direction['why_not']}")
    assert d.find_element("id", "verdict-model").text == api["model_version"]
    rows = d.find_elements("css selector", "#verdict-probs tbody tr")
    assert [r.get_attribute("data-class") for r in rows] == api["bands"]["names"]
    shown = sum(float(r.find_elements("tag name", "td")[1].text.split()[-2]) for r in rows)
    assert shown == pytest.approx(100.0, abs=0.25)
    names = [e.text for e in d.find_elements("css selector", "#verdict-features tbody code")]
    assert names == [f["name"] for f in api["top_features"]]
    assert d.find_element("id", "ood-warning").is_displayed() == bool(api["ood"])

    _screenshot(d, "verdict-laptop")
    plots = d.execute_script("return window.rotordiag.state.plots")
    assert [b["bearing"] for b in plots["bearings"]] == [1, 2, 3, 4]
    assert plots["speed_rpm"] == pytest.approx(api["speed_rpm"], rel=1e-9)
    for b in (1, 2, 3, 4):
        orbit = _canvas(d, f"orbit-{b}", BLUE_1X)
        assert abs(orbit["w"] - orbit["h"]) <= 1 and orbit["cw"] >= 250, orbit         # square, readable
        assert orbit["match"] > 150, orbit                                      # the 1X orbit was drawn
        for kind in ("half", "full"):
            spec = _canvas(d, f"{kind}-{b}", BLUE_1X if kind == "half" else VIOLET_FULL)
            assert abs(spec["w"] - 2 * spec["h"]) <= 1 and spec["cw"] >= 250, spec
            assert spec["match"] > 100, spec                                    # the spectrum lines were drawn
        # the plotted 1X orbit is the verdict's 1X: its major axis equals the feature b{n}_1x_major_um_pp
        f1x = plots["bearings"][b - 1]["orbit"]["filtered"]["1x"]
        major = 2 * max(np.hypot(x, y) for x, y in zip(f1x["x_um"], f1x["y_um"]))
        feats = next(x for x in api["bearings"] if x["bearing"] == b)["features"]
        assert major == pytest.approx(feats[f"b{b}_1x_major_um_pp"], rel=2e-3)
    # the log-scale switch redraws the spectra
    before = _canvas(d, "half-2", BLUE_1X)["ink"]
    d.find_element("id", "spectrum-scale").send_keys("log")
    _wait(d, lambda dr: _canvas(dr, "half-2", BLUE_1X)["ink"] != before, 10, "the log-scale redraw")


def test_the_page_says_which_model_answered_and_as_which_plant(server, browser, recordings, tmp_path):
    """The verdict's "Answered by" line: the API's `answered_by` sentence — the model, its training families, and
    the plant model chosen in the form (declared by the request) or none declared."""
    data = recordings[0.2]
    path = _write_csv(tmp_path / "unit.csv", data)
    _open(browser, server)
    d = browser
    _submit_file(d, path, sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM))
    page = d.execute_script("return window.rotordiag.state.verdict")["answered_by"]
    assert page["plant_model"] is None and page["model_version"] == _verdict_api(server, data)["model_version"]
    shown = d.find_element("id", "verdict-answered-by")
    assert shown.is_displayed() and shown.text == page["text"] and "no plant model declared" in shown.text
    d.find_element("id", "plant-model").send_keys("gen600_4pole")
    _submit_file(d, path, sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM))
    page = d.execute_script("return window.rotordiag.state.verdict")["answered_by"]
    assert (page["plant_model"], page["declared_by"]) == ("preset:gen600_4pole", "request")
    text = d.find_element("id", "verdict-answered-by").text
    assert text == page["text"] and "judged as gen600_4pole, declared by the request" in text
    _screenshot(d, "verdict-answered-by")
    d.find_element("id", "plant-model").send_keys("not stated")


def test_broken_uploads_show_the_services_message(server, browser, tmp_path):
    _open(browser, server)
    bad = tmp_path / "broken.csv"
    bad.write_text("probe_x,probe_y\n1.0,2.0\n3.0,oops\n")
    _submit_file(browser, bad, sample_rate="2048", expect="error")
    err = browser.find_element("id", "form-error")
    assert err.is_displayed() and "CSV file" in err.text and "oops" in err.text, err.text
    assert not browser.find_element("id", "verdict").is_displayed()
    assert not browser.find_element("id", "plots").is_displayed()
    _screenshot(browser, "error-broken-csv")

    junk = tmp_path / "junk.h5"
    junk.write_bytes(b"definitely not HDF5")
    _submit_file(browser, junk, sample_rate="2048", expect="error")
    assert "not an HDF5 file" in browser.find_element("id", "form-error").text

    # a pasted text that is not JSON never reaches the server
    browser.find_element("css selector", "input[name=source][value=json]").click()
    browser.find_element("id", "json-text").send_keys('{"sample_rate_hz": 2048, channels: []}')
    browser.execute_script("document.body.dataset.state = 'submitted'")
    browser.find_element("id", "diagnose-btn").click()
    _wait(browser, lambda d: d.execute_script("return document.body.dataset.state") == "error", 10, "the JSON error")
    assert "not valid JSON" in browser.find_element("id", "form-error").text


def test_asset_trend_after_three_diagnoses(server, browser, recordings, tmp_path):
    asset = "web-unit-7"
    _open(browser, server)
    # stored in the trend: the key typed in the form (an anonymous diagnosis is answered, not stored)
    _submit_file(browser, _write_npy(tmp_path / "a.npy", recordings[0.05]), asset=asset, sample_rate=str(FS_HZ),
                 clearance=str(CLEARANCE_UM), key="web-test-key")
    _submit_file(browser, _write_hdf5(tmp_path / "b.h5", recordings[0.2]), asset=asset,
                 key="web-test-key")  # rate from the file
    # the third as pasted JSON (set as the textarea's value: typing 150 kB is slow), rate from the form
    browser.find_element("css selector", "input[name=source][value=json]").click()
    browser.execute_script("document.getElementById('json-text').value = arguments[0]",
                           json.dumps(_json_body(recordings[0.45])))
    rate = browser.find_element("id", "sample-rate")
    rate.clear()
    rate.send_keys(str(FS_HZ))
    browser.execute_script("document.body.dataset.state = 'submitted'")
    browser.find_element("id", "diagnose-btn").click()
    _wait(browser, lambda d: d.execute_script("return document.body.dataset.state") in ("done", "error"), what="JSON")
    assert browser.execute_script("return document.body.dataset.state") == "done", \
        browser.find_element("id", "form-error").text

    status, history = _get(f"{server}/assets/{asset}/history")
    assert status == 200 and history["count"] == 3
    shown = browser.execute_script("return window.rotordiag.state.history")
    assert [p["misalignment"] for p in shown["points"]] == [p["misalignment"] for p in history["points"]]
    assert "3 diagnoses" in browser.find_element("id", "trend-info").text
    assert browser.find_element("id", "trend-plots").is_displayed()
    _screenshot(browser, "trend-laptop")
    delta = _canvas(browser, "trend-delta", GREEN_ALIGNED)
    assert delta["ink"] > 2000
    for k in ("1x", "2x"):
        amp = _canvas(browser, f"trend-{k}", *BEARING_COLOURS)        # one line per bearing, in its colour
        assert amp["match"] > 150, amp
        assert all(f"b1_{k}_major_um_pp" in p["amplitudes_um_pp"] for p in history["points"])
    # a trend asked for by hand, and an unknown asset's message
    browser.find_element("id", "trend-asset").clear()
    browser.find_element("id", "trend-asset").send_keys("no-such-asset")
    browser.find_element("id", "trend-btn").click()
    _wait(browser, lambda d: d.find_element("id", "trend-error").is_displayed(), 20, "the unknown-asset message")
    assert "no diagnosis stored" in browser.find_element("id", "trend-error").text
    browser.find_element("id", "trend-asset").clear()
    browser.find_element("id", "trend-asset").send_keys(asset)
    browser.find_element("id", "trend-btn").click()
    _wait(browser, lambda d: d.find_element("id", "trend-plots").is_displayed(), 20, "the trend")


@pytest.mark.parametrize("width,height,name", [(768, 1024, "tablet-portrait"), (1024, 768, "tablet-landscape")])
def test_tablet_layouts_fit_the_screen(server, browser, recordings, tmp_path, width, height, name):
    _open(browser, server, width, height)
    _submit_file(browser, _write_csv(tmp_path / "t.csv", recordings[0.45]), sample_rate=str(FS_HZ))
    time.sleep(0.3)
    overflow = browser.execute_script("return document.documentElement.scrollWidth - window.innerWidth")
    assert overflow <= 0, f"the page is {overflow} px wider than a {width} px screen"
    orbit = _canvas(browser, "orbit-2", BLUE_1X)
    assert orbit["match"] > 150 and 250 <= orbit["cw"] <= width
    half = browser.find_element("id", "half-2").rect
    assert half["x"] + half["width"] <= width
    upload, verdict = (browser.find_element("id", i).rect for i in ("upload", "verdict"))
    if width >= 1024:      # laptop layout: the verdict beside the form
        assert verdict["x"] >= upload["x"] + upload["width"]
    else:                  # tablet portrait: one column
        assert verdict["y"] >= upload["y"] + upload["height"]
    _screenshot(browser, name)


def test_api_docs_render_offline(server, browser):
    """/docs (Swagger UI) and /redoc (ReDoc) from the installed package: both render the operations and
    load nothing from anywhere but this server."""
    browser.get(server + "/docs")
    _wait(browser, lambda d: d.find_elements("css selector", ".opblock-summary-path"), 60, "the Swagger UI operations")
    paths = {e.text.replace("\u200b", "") for e in browser.find_elements("css selector", ".opblock-summary-path")}
    assert "/diagnose" in paths
    origins = browser.execute_script(
        "return performance.getEntriesByType('resource').map((r) => new URL(r.name).origin)")
    assert origins and set(origins) == {server}
    browser.get(server + "/redoc")
    _wait(browser, lambda d: [e for e in d.find_elements("css selector", "[role=menuitem], li[data-item-id]")
                              if "diagnose" in e.get_attribute("textContent").lower()], 60, "the ReDoc operations menu")
    origins = browser.execute_script(
        "return performance.getEntriesByType('resource').map((r) => new URL(r.name).origin)")
    assert origins and set(origins) == {server}


def test_try_an_example_recording(server, browser):
    """The shipped examples are listed and diagnosed through the same upload path as a user's file."""
    _open(browser, server)
    browser.find_element("css selector", "input[name=source][value=example]").click()
    assert browser.find_element("id", "example-fields").is_displayed()
    assert not browser.find_element("id", "file-fields").is_displayed()
    _wait(browser, lambda d: len(d.find_elements("css selector", "#example option")) >= 6, 30, "the example list")
    names = [o.get_attribute("value") for o in browser.find_elements("css selector", "#example option")]
    assert {"aligned.csv", "whirl.csv", "whirl_2560hz.npy", "whirl.h5", "whirl.uff"} <= set(names)
    for name in ("aligned.csv", "whirl_2560hz.npy"):
        Select(browser.find_element("id", "example")).select_by_value(name)
        browser.execute_script("document.body.dataset.state = 'submitted'")
        browser.find_element("id", "diagnose-btn").click()
        state = _wait(browser, lambda d: d.execute_script(
            "const s = document.body.dataset.state; return s === 'done' || s === 'error' ? s : null"), what=name)
        assert state == "done", browser.find_element("id", "form-error").text
        verdict = browser.execute_script("return window.rotordiag.state.verdict")
        if name.startswith("aligned"):
            assert verdict["severity"] == "aligned", (name, verdict["severity"])
        else:   # never confidently wrong
            assert not (verdict["model_severity"] == "aligned" and verdict["status"] == "confident"), verdict
    _screenshot(browser, "example-npy")


def test_form_errors_are_in_plain_words(server, browser, tmp_path):
    """A file without a sample rate asks for the form's field, not for a query parameter."""
    _open(browser, server)
    arr = tmp_path / "bare.npy"
    np.save(arr, np.random.default_rng(3).normal(size=(8, 4096)))
    _submit_file(browser, arr, expect="error")
    text = browser.find_element("id", "form-error").text
    assert "Fill in the sample rate (Hz)" in text, text
    assert "sample_rate_hz" not in text and "CLI" not in text, text


def test_lengths_in_mils(server, browser):
    """With "Lengths in: mil" the offset, the evidence and the plot axes are in mils."""
    _open(browser, server)
    browser.find_element("css selector", "input[name=source][value=example]").click()
    _wait(browser, lambda d: len(d.find_elements("css selector", "#example option")) >= 6, 30, "the example list")
    Select(browser.find_element("id", "example")).select_by_value("whirl.csv")
    Select(browser.find_element("id", "length-units")).select_by_value("mil")
    clearance = browser.find_element("id", "clearance")
    clearance.clear()
    clearance.send_keys("350")
    browser.execute_script("document.body.dataset.state = 'submitted'")
    browser.find_element("id", "diagnose-btn").click()
    state = _wait(browser, lambda d: d.execute_script(
        "const s = document.body.dataset.state; return s === 'done' || s === 'error' ? s : null"), what="the verdict")
    assert state == "done", browser.find_element("id", "form-error").text
    verdict = browser.execute_script("return window.rotordiag.state.verdict")
    assert verdict["output_units"] == "mil" and verdict["offset_mil"] > 0
    assert browser.find_element("id", "verdict-offset").text.split()[1] == "mil"
    assert "µm" not in browser.find_element("id", "verdict-evidence").text
    labels = browser.execute_script(
        "return [...document.querySelectorAll('canvas')].filter((c) => c._spec).map((c) => c._spec.y.label)")
    assert labels and all("µm" not in lab for lab in labels) and any("mil" in lab for lab in labels), labels
    _screenshot(browser, "lengths-in-mils")
    reasons = browser.find_element("id", "verdict-reasons").text
    assert "speed_rpm" not in reasons and "keyphasor_times_s" not in reasons, reasons


def test_baseline_and_change_are_shown(server, browser, recordings, tmp_path):
    """An asset with a baseline (set through the API from its first diagnosis): a later, more misaligned
    recording diagnosed on the page shows that the baseline was used and what changed; the trend shows
    the baseline and the raised alarm."""
    asset = "web-base-1"
    body = {"sample_rate_hz": FS_HZ, "clearance_um": CLEARANCE_UM, "asset_id": asset, **_json_body(recordings[0.05])}
    req = urllib.request.Request(server + "/diagnose", data=json.dumps(body).encode(),
                                 headers={"Content-Type": "application/json", "X-API-Key": "web-test-key"})
    with urllib.request.urlopen(req, timeout=120) as r:
        first = json.loads(r.read())
    req = urllib.request.Request(f"{server}/assets/{asset}/baseline?diagnosis_id={first['diagnosis_id']}",
                                 data=b"", method="POST", headers={"X-API-Key": "web-test-key"})
    with urllib.request.urlopen(req, timeout=60) as r:
        base = json.loads(r.read())
    assert base["source"] == "diagnosis"
    status, shown = _get(f"{server}/assets/{asset}/baseline")
    same = shown["thresholds"]["orbit_2x_1x_change"]          # an edit to the same value: origin "edited"
    req = urllib.request.Request(f"{server}/assets/{asset}/thresholds", method="PUT",
                                 data=json.dumps({"thresholds": {"orbit_2x_1x_change": same}}).encode(),
                                 headers={"X-API-Key": "web-test-key", "Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=60) as r:
        assert json.loads(r.read())["thresholds_origin"]["orbit_2x_1x_change"] == "edited"

    _open(browser, server)
    _submit_file(browser, _write_npy(tmp_path / "later.npy", recordings[0.45]), asset=asset,
                 sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM), key="web-test-key")
    box = browser.find_element("id", "verdict-baseline")
    assert box.is_displayed()
    set_at = readable_time(base["set_at"])
    assert f"Baseline of {set_at} used" in box.text and "changed since the baseline" in box.text
    assert "Alarm thresholds: the fleet-wide ones (1 baseline recording;" in box.text, box.text
    assert "_change" not in box.text and "dc_shift" not in box.text and re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC", set_at)
    assert "changed" in box.get_attribute("class").split()
    rows = browser.find_elements("css selector", "#verdict-evidence tbody tr")
    assert any(r.text.startswith("change since baseline") and "CHANGED" in r.text for r in rows)
    _wait(browser, lambda d: d.find_element("id", "trend-baseline-box").is_displayed(), 30, "the baseline in the trend")
    trend = browser.find_element("id", "trend-baseline").text
    assert "from diagnosis" in trend and "Alarm thresholds of this asset edited: orbit 2X/1X change" in trend, trend
    assert "the others shipped" in trend, trend
    alarms = browser.find_element("id", "trend-alarms").text
    status, history = _get(f"{server}/assets/{asset}/history")
    assert history["alarms"][0]["event"] == "raised"
    names = {"1x_change": "1X vector change", "2x_change": "2X vector change", "dc_shift": "centreline shift",
             "orbit_ellipticity_change": "orbit ellipticity change", "orbit_2x_1x_change": "orbit 2X/1X change"}
    assert f"alarm raised ({', '.join(names[q] for q in history['alarms'][0]['quantities'])})" in alarms
    assert f"{readable_time(history['alarms'][0]['time'])}: alarm raised" in alarms
    assert " 1\n" not in alarms + "\n" and not re.search(r"\d 1(;|$)", alarms, re.M)   # no "0.313 1"
    _screenshot(browser, "baseline-changed")


def test_baseline_is_set_from_the_page(server, browser, recordings):
    """The trend's baseline form: refused without the key and with a wrong one (the service's words shown),
    then an automatic baseline (3 stored recordings; the asset's own thresholds listed) and the latest
    diagnosis made the baseline, each shown in the trend after the click."""
    asset = "web-base-2"
    rng = np.random.default_rng(5)
    for _ in range(3):
        data = recordings[0.05] + 0.05 * rng.standard_normal(recordings[0.05].shape)
        body = {"sample_rate_hz": FS_HZ, "clearance_um": CLEARANCE_UM, "asset_id": asset, **_json_body(data)}
        req = urllib.request.Request(server + "/diagnose", data=json.dumps(body).encode(),
                                     headers={"Content-Type": "application/json", "X-API-Key": "web-test-key"})
        with urllib.request.urlopen(req, timeout=120) as r:
            assert r.status == 200
    _open(browser, server)
    browser.find_element("id", "trend-asset").send_keys(asset)
    browser.find_element("id", "trend-btn").click()
    _wait(browser, lambda d: d.find_element("id", "trend-baseline-box").is_displayed(), 30, "the baseline box")
    assert "None set. Automatic proposal" in browser.find_element("id", "trend-baseline").text
    browser.find_element("id", "baseline-auto-btn").click()
    err = browser.find_element("id", "baseline-error")
    assert err.is_displayed() and "API key" in err.text
    browser.find_element("id", "baseline-key").send_keys("wrong-key")
    browser.find_element("id", "baseline-auto-btn").click()
    _wait(browser, lambda d: "key" in d.find_element("id", "baseline-error").text.lower()
          and "Type the API key" not in d.find_element("id", "baseline-error").text, 20, "the wrong-key message")
    browser.find_element("id", "baseline-key").clear()
    browser.find_element("id", "baseline-key").send_keys("web-test-key")
    browser.find_element("id", "baseline-auto-btn").click()
    _wait(browser, lambda d: "from auto" in d.find_element("id", "trend-baseline").text, 30, "the automatic baseline")
    text = browser.find_element("id", "trend-baseline").text
    assert "from its baseline recordings' repeatability: 1X vector change" in text, text
    assert "centreline shift" in text and "per c" not in text, text
    assert not browser.find_element("id", "baseline-error").is_displayed()
    _screenshot(browser, "baseline-set-from-page")
    browser.find_element("id", "baseline-latest-btn").click()
    _wait(browser, lambda d: "from diagnosis" in d.find_element("id", "trend-baseline").text, 30, "the latest as baseline")
    status, b = _get(f"{server}/assets/{asset}/baseline")
    _, h = _get(f"{server}/assets/{asset}/history")
    assert b["baseline"]["source"] == "diagnosis" and b["baseline"]["diagnosis_ids"] == [h["points"][-1]["id"]]
    text = browser.find_element("id", "trend-baseline").text
    assert "made of 1 recording" in text and "shipped, fleet-wide ones — this baseline has 1 recording" in text, text
    # adding the latest diagnosis again: the service refuses it (already in the baseline), in its words
    browser.find_element("id", "baseline-add-btn").click()
    _wait(browser, lambda d: "already in the baseline" in d.find_element("id", "baseline-error").text, 20,
          "the refusal to add a recording twice")
    # the first stored recording added: a baseline of 2, still the fleet-wide thresholds
    req = urllib.request.Request(f"{server}/assets/{asset}/baseline/recordings?diagnosis_id={h['points'][0]['id']}",
                                 method="POST", headers={"X-API-Key": "web-test-key"})
    with urllib.request.urlopen(req, timeout=60) as r:
        assert json.loads(r.read())["n_recordings"] == 2
    browser.find_element("id", "trend-btn").click()
    _wait(browser, lambda d: "made of 2 recordings" in d.find_element("id", "trend-baseline").text, 30,
          "the baseline of 2 recordings")


def test_speed_range_field(server, browser, recordings, tmp_path):
    """The nominal speed range goes with the upload: inside it the speed is estimated as without it; a range
    with min ≥ max is refused in the form's words."""
    path = _write_npy(tmp_path / "range.npy", recordings[0.05])
    _open(browser, server)
    browser.find_element("id", "speed-range").send_keys("1700,1900")
    _submit_file(browser, path, sample_rate=str(FS_HZ))
    verdict = browser.execute_script("return window.rotordiag.state.verdict")
    assert verdict["speed_rpm"] == pytest.approx(SPEED_RPM, rel=5e-3)
    browser.find_element("id", "speed-range").clear()
    browser.find_element("id", "speed-range").send_keys("1900,1700")
    _submit_file(browser, path, sample_rate=str(FS_HZ), expect="error")
    text = browser.find_element("id", "form-error").text
    assert "the nominal speed range (r/min)" in text and "speed_range_rpm" not in text, text


def test_dc_removed_checkbox(server, browser, recordings, tmp_path):
    """An AC-coupled upload ticked as such: the centreline evidence says it was not measured and the verdict's
    warnings say why; unticked, the same file's DC part is read as the shaft position."""
    path = _write_npy(tmp_path / "ac.npy", recordings[0.05])
    _open(browser, server)
    box = browser.find_element("id", "dc-removed")
    assert not box.is_selected() and browser.find_element("css selector", "label[for=dc-removed]").is_displayed()
    _submit_file(browser, path, sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM))
    plain = browser.execute_script("return window.rotordiag.state.verdict")
    box.click()
    _submit_file(browser, path, sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM))
    ticked = browser.execute_script("return window.rotordiag.state.verdict")
    centre = [e["value"] for e in ticked["evidence"] if e["name"] == "shaft centreline"]
    assert centre and all(v == "not measured: the channels carry no DC position" for v in centre)
    assert all(e["value"] != "not measured: the channels carry no DC position"
               for e in plain["evidence"] if e["name"] == "shaft centreline")
    assert "not measured: the channels carry no DC position" in browser.find_element("tag name", "body").text
    _screenshot(browser, "dc_removed")


def test_acquisitions_field(server, browser, recordings, tmp_path):
    """Bearings 1-2 and 3-4 stated as separate takes: the coupling's phase evidence says it was not measured, the
    verdict is not confident and says why; a grouping that leaves a bearing out is a form error in plain words."""
    path = _write_npy(tmp_path / "takes.npy", recordings[0.2])
    _open(browser, server)
    field = browser.find_element("id", "acquisitions")
    assert browser.find_element("css selector", "label[for=acquisitions]").is_displayed()
    field.clear()
    field.send_keys("1,2;3,4")
    _submit_file(browser, path, sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM))
    v = browser.execute_script("return window.rotordiag.state.verdict")
    assert v["status"] != "confident" and "separate_acquisitions" in [r["code"] for r in v["reasons"]]
    body = browser.find_element("tag name", "body").text
    assert "not measured (bearings 2 and 3 recorded in separate acquisitions)" in body
    assert "record bearings 2 and 3 in one acquisition" in body
    _screenshot(browser, "acquisitions")
    field.clear()
    field.send_keys("1,2;3")
    _submit_file(browser, path, sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM), expect="error")
    text = browser.find_element("id", "form-error").text
    assert "bearing 4 is recorded but in no acquisition" in text, text
    field.clear()


def test_a_keyphasor_channel_per_take(server, browser, recordings, tmp_path):
    """Bearings 1-2 and 3-4 in two takes, the second 7 ms later, each with its keyphasor channel (rows 8 and 9 of
    an NPY file): with both stated on the page the phase across the coupling is measured — no
    `separate_acquisitions`, and the evidence gives the phase — and the orbits are drawn from each take's pulses."""
    data = recordings[0.2].T.astype(float)                  # (8, n) probes
    late = int(round(0.007 * FS_HZ))
    takes = data.copy()
    takes[4:, :-late] = data[4:, late:]
    takes = takes[:, :-late]
    n = takes.shape[1]
    period = 60.0 / SPEED_RPM
    t = np.arange(n) / FS_HZ
    kp = np.zeros((2, n))
    for row, shift in ((0, 0.0), (1, late / FS_HZ)):
        phase = ((t + shift - 0.3 * period) / period) % 1.0
        kp[row] = np.where(phase < 0.05, -12.0, -8.0)          # a notch 5 % of a revolution wide
    path = tmp_path / "takes_kp.npy"
    np.save(path, np.vstack([takes, kp]).astype(np.float32))
    _open(browser, server)
    assert browser.find_element("css selector", "label[for=keyphasor-channel]").is_displayed()
    browser.find_element("id", "acquisitions").send_keys("1,2;3,4")
    browser.find_element("id", "keyphasor-channel").send_keys("8;9")
    _submit_file(browser, path, sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM))
    v = browser.execute_script("return window.rotordiag.state.verdict")
    assert "separate_acquisitions" not in [r["code"] for r in v["reasons"]], v["reasons"]
    assert v["speed_source"] == "keyphasor" and any("each with its keyphasor" in w for w in v["warnings"])
    body = browser.find_element("tag name", "body").text
    assert "not measured (bearings 2 and 3 recorded in separate acquisitions)" not in body
    plot = browser.execute_script("return window.rotordiag.state.plots")
    assert plot["phase_reference"] == "keyphasor" and len(plot["bearings"]) == 4
    _screenshot(browser, "keyphasor_per_take")
    browser.find_element("id", "keyphasor-channel").clear()
    browser.find_element("id", "acquisitions").clear()


def test_takes_saved_as_separate_files(server, browser, recordings, tmp_path):
    """A portable analyser's two takes as two CSV files (bearings 1-2, then 3-4 7 ms later), each with its `kp`
    column, chosen together on the page: one recording with a keyphasor per take — the phase across the coupling is
    measured (no `separate_acquisitions`), the orbits of all four bearings drawn; a bearing in both files is refused
    naming it."""
    data = recordings[0.2]
    rec = (FS_HZ, [(b, a, data[:, 2 * (b - 1) + j]) for b in (1, 2, 3, 4) for j, a in enumerate((45.0, 135.0))])
    t, first, second, kp_a, kp_b, _, names = two_takes(rec)            # (two_takes' keyphasor: 1800 r/min)
    paths = [write_takes_csv(tmp_path / "take_a.csv", t, [*first, kp_a], [*names[:4], "kp"]),
             write_takes_csv(tmp_path / "take_b.csv", t, [*second, kp_b], [*names[4:], "kp"])]
    _open(browser, server)
    _submit_file(browser, paths, sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM))
    v = browser.execute_script("return window.rotordiag.state.verdict")
    assert "separate_acquisitions" not in [r["code"] for r in v["reasons"]], v["reasons"]
    assert v["speed_source"] == "keyphasor" and any("each with its keyphasor" in w for w in v["warnings"])
    plot = browser.execute_script("return window.rotordiag.state.plots")
    assert plot["phase_reference"] == "keyphasor" and sorted(b["bearing"] for b in plot["bearings"]) == [1, 2, 3, 4]
    _screenshot(browser, "take_files")
    _submit_file(browser, [paths[0], paths[0]], sample_rate=str(FS_HZ), expect="error")
    text = browser.find_element("id", "form-error").text
    assert "bearing 1 is in two takes" in text, text


def test_probes_only_at_bearings_1_3_4_and_1_4(server, browser, recordings, tmp_path):
    """rotordiag.models.checks.bearing_sets on the page: probes at 1, 3, 4 are read from bearing 3 (a warning says so, the evidence
    keeps every bearing; never confident when the shipped table calls bearing 3 alone weak — v0001 did, v0002 does
    not; no severity when it calls it uninformative — v0004), and the page says which set it read; probes at 1 and 4
    alone give no severity and say what to add."""
    from rotordiag.models.checks import bearing_sets as bs
    from tests.service_util import shipped_registry_usable

    if not shipped_registry_usable():
        pytest.skip("the tiny registry lists no training probe sets")
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.registry import shipped_registry_dir

    table = bs.load_capability(load_bundle(shipped_registry_dir()).card)
    assert table is not None, "the shipped probe-set table was measured for another model"
    weak = table["3"]["false_alarm"] > bs.MAX_FALSE_ALARM
    informative = bs.informative(table["3"])
    data = recordings[0.2]
    d = browser
    for keep, name in (((1, 3, 4), "probes_134"), ((1, 4), "probes_14")):
        cols = [2 * (b - 1) + j for b in keep for j in (0, 1)]
        path = tmp_path / f"{name}.csv"
        header = ",".join(f"b{b}_{a:g}deg_um" for b in keep for a in (45, 135))
        np.savetxt(path, data[:, cols], delimiter=",", header=header, comments="", fmt="%.6f")
        _open(d, server)
        _submit_file(d, path, sample_rate=str(FS_HZ), clearance=str(CLEARANCE_UM))
        page = d.execute_script("return window.rotordiag.state.verdict")
        codes = [r["code"] for r in page["reasons"]]
        reasons = " ".join(e.text for e in d.find_elements("css selector", "#verdict-reasons li"))
        if keep == (1, 4):
            assert page["status"] == "inconclusive" and not d.find_element("id", "verdict-severity-row").is_displayed()
            assert "bearings 1 and 4" in reasons and "coupling bearing" in reasons
        elif not informative:
            assert page["status"] == "inconclusive" and codes[0] == "bearing_set_uninformative"
            assert "the model reads bearing 3" in reasons and not d.find_element("id", "verdict-severity-row").is_displayed()
        else:
            assert ("bearing_set_weak" in codes) == weak and (page["status"] == "uncertain" or not weak)
            assert any("bearings 1 and 4 not read by the model" in w for w in page["warnings"])
        _screenshot(d, name)


def test_mains_pickup_is_named_and_removed_before_the_severity(server, browser, recordings, tmp_path):
    """A 12 µm 2X on every channel (mains pickup on a grid-synchronous generator): the page shows the reasons that
    name it and say that it was removed before the verdict; never a confident verdict."""
    data = recordings[0.05]
    t = np.arange(data.shape[0]) / FS_HZ
    hum = 12.0 * np.cos(2 * np.pi * 2 * SPEED_RPM / 60.0 * t)[:, None]
    _open(browser, server)
    _submit_file(browser, _write_csv(tmp_path / "pickup.csv", data + hum), sample_rate=str(FS_HZ),
                 clearance=str(CLEARANCE_UM))
    d = browser
    page = d.execute_script("return window.rotordiag.state.verdict")
    assert page["status"] != "confident" and "common_mode_2x" in [r["code"] for r in page["reasons"]]
    assert "common_mode" in [r["code"] for r in page["reasons"]]
    reasons = " ".join(e.text for e in d.find_elements("css selector", "#verdict-reasons li"))
    assert "grounding" in reasons and "removed from every probe" in reasons
    _screenshot(d, "mains-pickup")


def test_a_daq_export_in_mv_with_columns_mapped_by_name(server, browser, tmp_path):
    """A DAQ export as it comes (Time [ms], a unit row, probe output in mV, a temperature column): the page's
    column mapping, units, sensitivity and gap-voltage fields read it, and the answer says how it was read."""
    from rotordiag.features.examples import example_path
    from rotordiag.features.reader import read_recording
    from tests.collector_exports import DAQ_SENSITIVITY, GAP_V, mapping, write_daq_csv

    rec = read_recording(example_path("whirl.csv")).recording
    path = tmp_path / "daq.csv"
    names = write_daq_csv(path, np.stack([c.data for c in rec.channels]), rec.sample_rate_hz)
    _open(browser, server)
    browser.find_element("id", "channel-map").send_keys(mapping(names))
    Select(browser.find_element("id", "units")).select_by_value("mV")
    browser.find_element("id", "sensitivity").send_keys(DAQ_SENSITIVITY)
    browser.find_element("id", "gap-voltage").send_keys(str(GAP_V))
    _submit_file(browser, path)
    verdict = browser.execute_script("return window.rotordiag.state.verdict")
    notes = verdict["input_notes"]
    assert "column(s) ['BRG 2 TEMP'] are neither time, keyphasor nor in the channel mapping: not read" in notes
    shown = browser.find_element("id", "verdict-input-notes").text
    assert "BRG 2 TEMP" in shown and "7.874 V/mm" in shown, shown
    browser.find_element("id", "sensitivity").clear()
    _submit_file(browser, path, expect="error")
    text = browser.find_element("id", "form-error").text
    assert "give the probe sensitivity" in text, text


def test_startup_recording_shows_its_plots_and_an_asset_its_report_link(server, browser, recordings, tmp_path):
    """A run-up uploaded on the page (button "Start-up / coast-down plots"): the Bode, polar, cascade, full spectrum
    and centreline PNGs are shown and decoded by the browser, with the 1X peaks; a broken file's message is shown in
    that section. An asset's trend links its report, which opens as a page with its embedded trend plot."""
    from typer.testing import CliRunner

    from rotordiag.cli import app

    runup = tmp_path / "runup.csv"
    r = CliRunner().invoke(app, ["runup", "--profile", "900:1500:6", "--misalignment", "0.3", "--out", str(runup)])
    assert r.exit_code == 0, r.output
    d = browser
    _open(d, server)
    d.find_element("css selector", "input[name=source][value=file]").click()
    chooser = d.find_element("id", "file")
    chooser.clear()
    chooser.send_keys(str(runup))
    d.execute_script("document.body.dataset.state = 'submitted'")
    d.find_element("id", "transient-btn").click()
    state = _wait(d, lambda dr: dr.execute_script(
        "const s = document.body.dataset.state; return s === 'done' || s === 'error' ? s : null"), what="the plots")
    assert state == "done", d.find_element("id", "transient-error").text
    shown = d.execute_script("""return [...document.querySelectorAll('#transient-figures figure')].map((f) => {
        const img = f.querySelector('img'); return [f.dataset.name, img.complete && img.naturalWidth, img.clientWidth]; })""")
    names = {n for n, _, _ in shown}
    assert {"bode", "polar", "waterfall_b1", "full_spectrum_b1", "centreline", "orbits"} <= names, shown
    assert all(natural and natural > 300 and width > 200 for _, natural, width in shown), shown
    assert "run-up" in d.find_element("id", "transient-info").text
    peaks = d.find_element("id", "transient-peaks").text
    assert "1X peak at bearing 1 @ 45°" in peaks and "µm pk-pk" in peaks, peaks
    assert not d.find_element("id", "verdict").is_displayed()     # plotted, not diagnosed
    _screenshot(d, "startup-plots")
    # a broken file: the service's message in the start-up section
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,a\n0,zz\n")
    chooser.clear()
    chooser.send_keys(str(bad))
    d.find_element("id", "transient-btn").click()
    _wait(d, lambda dr: dr.find_element("id", "transient-error").is_displayed(), 60, "the start-up error")
    assert "could not be drawn" in d.find_element("id", "transient-error").text
    assert not d.find_elements("css selector", "#transient-figures figure")   # no earlier plots beside the error
    # the asset's report link, after a stored diagnosis
    asset = "web-report-1"
    _submit_file(d, _write_npy(tmp_path / "a.npy", recordings[0.2]), asset=asset, sample_rate=str(FS_HZ),
                 clearance=str(CLEARANCE_UM), key="web-test-key")
    _wait(d, lambda dr: dr.find_element("id", "trend-report").is_displayed(), 30, "the report link")
    pdf_href = d.find_element("id", "trend-report-pdf").get_attribute("href")
    with urllib.request.urlopen(pdf_href, timeout=120) as resp:
        assert resp.headers["Content-Type"] == "application/pdf" and resp.read(5) == b"%PDF-"
    d.find_element("id", "trend-report-html").click()
    _wait(d, lambda dr: "rotordiag report" in dr.title, 120, "the HTML report")
    assert d.find_element("tag name", "h1").text == f"rotordiag report — {asset}"
    assert d.execute_script("const i = document.querySelector('img'); return i.complete && i.naturalWidth") > 300
    _screenshot(d, "asset-report-html")


def test_a_startup_is_stored_on_the_asset_from_the_page_and_listed_in_its_trend(server, browser, recordings, tmp_path):
    """Two run-ups of the paper model uploaded on the page and stored on an asset (button "Store this start-up on
    the asset"): the first as the asset's baseline start-up, then one at Δ 0.15 — whose coupling-end centreline
    rise moved (docs/transient.md: 20/20 held-out plants) — is compared with it, and the asset's confident
    "aligned" verdict of a steady Δ 0 recording (1950 r/min, as tests/test_service_startup.py) is shown uncertain
    with the reason. Without the asset id the
    page says what to type. The asset's trend lists both start-ups, which one is the baseline."""
    from typer.testing import CliRunner

    from rotordiag.cli import app

    runs = {}
    for name, delta, seed in (("base", "0", "1"), ("changed", "0.15", "3")):
        runs[name] = tmp_path / f"{name}.csv"
        r = CliRunner().invoke(app, ["runup", "--profile", "300:2000:17", "--misalignment", delta, "--settle-revs",
                                     "100", "--seed", seed, "--out", str(runs[name])])
        assert r.exit_code == 0, r.output
    steady = tmp_path / "steady.csv"
    r = CliRunner().invoke(app, ["simulate", "--speed-rpm", "1950", "--misalignment", "0", "--record-revs", "80",
                                 "--probes-out", str(steady), "--probe-sample-rate-hz", "2560"])
    assert r.exit_code == 0, r.output
    d = browser
    _open(d, server)
    asset = "web-startup-1"
    _submit_file(d, steady, asset=asset, clearance=str(CLEARANCE_UM), key="web-test-key")
    assert "aligned" in d.find_element("id", "verdict-severity").text.lower()

    def plot_and_store(path: Path, baseline: bool) -> str:
        for field in ("sample-rate", "clearance"):
            d.find_element("id", field).clear()
        chooser = d.find_element("id", "file")
        chooser.clear()
        chooser.send_keys(str(path))
        d.execute_script("document.body.dataset.state = 'submitted'")
        d.find_element("id", "transient-btn").click()
        _wait(d, lambda dr: dr.execute_script("return document.body.dataset.state") in ("done", "error"),
              what="the start-up plots")
        assert d.find_elements("css selector", "#transient-figures figure"), d.find_element("id", "transient-error").text
        box = d.find_element("id", "transient-baseline")
        if box.is_selected() != baseline:
            box.click()
        d.execute_script("document.body.dataset.state = 'submitted'")
        d.find_element("id", "transient-store-btn").click()
        state = _wait(d, lambda dr: dr.execute_script(
            "const s = document.body.dataset.state; return s === 'done' || s === 'error' ? s : null"),
            what="the stored start-up")
        assert state == "done", d.find_element("id", "transient-store-error").text
        return d.find_element("id", "transient-stored-info").text

    info = plot_and_store(runs["base"], baseline=True)
    assert f"of {asset}, the asset's baseline start-up" in info, info
    info = plot_and_store(runs["changed"], baseline=False)
    assert "a later start-up; compared with baseline start-up #" in info, info
    assert "aligned (uncertain)" in info and "investigate" in info, info
    rows = d.find_element("id", "transient-stored-rows").text
    assert "coupling end" in rows and "baseline" in rows, rows
    assert d.find_elements("css selector", "#transient-stored-rows li.effect-doubts")
    _screenshot(d, "startup-stored")
    # no asset id: what to type, nothing stored
    d.find_element("id", "asset").clear()
    d.find_element("id", "transient-store-btn").click()
    assert "Type the asset id" in d.find_element("id", "transient-store-error").text
    assert not d.find_element("id", "transient-stored").is_displayed()
    # the asset's trend lists its start-ups
    d.find_element("id", "trend-asset").clear()
    d.find_element("id", "trend-asset").send_keys(asset)
    d.find_element("id", "trend-btn").click()

    def listed_items(dr):  # read in one go: the list may be re-drawn between finding and reading an item
        texts = [li.text for li in dr.find_elements("css selector", "#trend-startups li")]
        return texts if len(texts) == 2 else None

    items = _wait(d, listed_items, 60, "the start-ups list")
    assert "baseline start-up" in items[1] and "compared with the baseline in the verdicts" in items[0], items
    assert "r/min" in items[0] and "half-rise" in items[0], items
    status, listed = _get(f"{server}/assets/{asset}/startups")
    assert status == 200 and len(listed["startups"]) == 2 and listed["startups"][1]["is_baseline"], listed
    _screenshot(d, "asset-startups")


def test_trend_orders_by_recording_time_and_lists_notes(server, browser, recordings):
    """Two recordings sent out of order (the second backfilled with a note and operating state): the page's
    trend has the backfilled one first and lists its note and tags, and the setpoint alarm, in the trend area."""
    import urllib.parse

    asset = "web-backfill"

    def post(query: str, rec) -> dict:
        req = urllib.request.Request(f"{server}/diagnose?{query}", data=json.dumps(
            {**_json_body(rec), "sample_rate_hz": FS_HZ, "asset_id": asset}).encode(), method="POST",
            headers={"Content-Type": "application/json", "X-API-Key": "web-test-key"})
        with urllib.request.urlopen(req, timeout=120) as r:
            return json.loads(r.read())

    req = urllib.request.Request(f"{server}/assets/{asset}/setpoints", method="PUT", data=json.dumps(
        {"setpoints": {"x1_um_pp": {"alert": 0.001}}}).encode(),
        headers={"Content-Type": "application/json", "X-API-Key": "web-test-key"})
    urllib.request.urlopen(req, timeout=60).close()
    live = post("recorded_at=2026-06-01T10:00:00Z", recordings[0.05])
    back = post(urllib.parse.urlencode({"recorded_at": "2025-01-15T08:00:00Z", "note": "aligned on 2025-01-14",
                                        "tags": "load_mw=350;stator_temp_c=71"}), recordings[0.2])
    _open(browser, server)
    browser.find_element("id", "trend-asset").clear()
    browser.find_element("id", "trend-asset").send_keys(asset)
    browser.find_element("id", "trend-btn").click()
    _wait(browser, lambda d: d.find_element("id", "trend-plots").is_displayed(), 60, "the trend")
    shown = browser.execute_script("return window.rotordiag.state.history")
    assert [p["id"] for p in shown["points"]] == [back["diagnosis_id"], live["diagnosis_id"]]
    _wait(browser, lambda d: "aligned on 2025-01-14" in d.find_element("id", "trend-alarms").text, 30, "the note")
    text = browser.find_element("id", "trend-alarms").text
    assert "load mw 350" in text and "stator temp c 71" in text and f"diagnosis {back['diagnosis_id']}" in text
    # the setpoint alarm the live recording raised, not yet acknowledged
    assert "alert raised: 1X" in text and "(alert setpoint 0.001)" in text and "not acknowledged" in text


def test_an_upload_with_its_time_state_and_note_and_the_asset_tree(server, browser, recordings, tmp_path):
    """The upload form's recording time, operating state and note are stored with the diagnosis (the trend lists
    them at that time); the asset is then placed site → unit → train from the trend area and shows in the tree."""
    asset = "web-tree-1"
    _open(browser, server)
    d = browser
    for field, value in (("tags", "load_mw=320;stator_temp_c=68"), ("note", "after the March outage")):
        d.find_element("id", field).clear()
        d.find_element("id", field).send_keys(value)
    d.execute_script("document.getElementById('recorded-at').value = '2025-03-04T09:15:00'")
    _submit_file(d, _write_csv(tmp_path / "t.csv", recordings[0.05]), asset=asset, sample_rate=str(FS_HZ),
                 clearance=str(CLEARANCE_UM), key="web-test-key")
    status, history = _get(f"{server}/assets/{asset}/history")
    p = history["points"][-1]
    assert p["trend_time"].startswith("2025-03-04T09:15") and p["note"] == "after the March outage"
    assert p["tags"] == {"load_mw": 320.0, "stator_temp_c": 68.0}
    d.find_element("id", "trend-asset").clear()
    d.find_element("id", "trend-asset").send_keys(asset)
    d.find_element("css selector", "#assets-box summary").click()
    for field, value in (("hier-site", "Riverside"), ("hier-unit", "unit 3"), ("hier-train", "generator-exciter"),
                         ("hier-key", "web-test-key")):
        d.find_element("id", field).send_keys(value)
    d.find_element("id", "hier-btn").click()
    _wait(d, lambda dr: "Riverside → unit 3 → generator-exciter" in dr.find_element("id", "assets-tree").text, 30,
          "the asset in the tree")
    tree = d.find_element("id", "assets-tree").text
    assert f"{asset} (1 recording, latest 2025-03-04 09:15 UTC)" in tree, tree
    d.find_element("css selector", f"button[data-asset='{asset}']").click()
    _wait(d, lambda dr: "after the March outage" in dr.find_element("id", "trend-alarms").text, 60, "the trend's note")
    assert "2025-03-04 09:15 UTC: after the March outage — load mw 320, stator temp c 68" in \
        d.find_element("id", "trend-alarms").text
    _screenshot(d, "asset_tree")


def test_rollback_button_restores_the_previous_model(server, browser):
    """The Models card's rollback button: refused without the API key (the service's words shown), then one
    click re-activates the version that was active before (POST /models/rollback), shown in the table."""
    reg = REGISTRIES[server]
    before = _get(server + "/models")[1]["active"]
    new = f"v{int(before[1:]) + 1:04d}"
    shutil.copytree(reg / before, reg / new)                 # the same model under a new version
    card = json.loads((reg / new / "card.json").read_text())
    (reg / new / "card.json").write_text(json.dumps({**card, "version": new}))
    req = urllib.request.Request(f"{server}/models/{new}/activate", data=b"", method="POST",
                                 headers={"X-API-Key": "web-test-key"})
    with urllib.request.urlopen(req, timeout=60) as r:
        assert r.status == 200
    _open(browser, server)
    _wait(browser, lambda d: "active" in d.find_element("css selector", f"#models-table tr[data-version='{new}']").text,
          30, "the new version active in the table")
    browser.find_element("id", "rollback-btn").click()
    _wait(browser, lambda d: d.find_element("id", "rollback-error").is_displayed(), 20, "the missing-key message")
    assert "key" in browser.find_element("id", "rollback-error").text.lower()
    assert _get(server + "/models")[1]["active"] == new
    browser.find_element("id", "rollback-key").send_keys("web-test-key")
    browser.find_element("id", "rollback-btn").click()
    _wait(browser, lambda d: f"Active model: {before} (was {new})" in d.find_element("id", "rollback-done").text, 30,
          "the rollback's answer")
    _wait(browser, lambda d: "active" in d.find_element("css selector",
                                                      f"#models-table tr[data-version='{before}']").text,
          30, "the previous version active in the table")
    assert not browser.find_element("id", "rollback-error").is_displayed()
    assert _get(server + "/models")[1]["active"] == before
    _screenshot(browser, "models-rollback")
