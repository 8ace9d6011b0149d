"""The web page's plant card in a real browser (Debian chromium + selenium, the fixtures of
tests/test_web_browser.py): a preset's or an uploaded shaft line's train summary from POST /trains/summary."""
from __future__ import annotations

import json
import urllib.request

from tests.test_web_browser import ROOT, Select, _get, _open, _screenshot, _wait, browser, server  # noqa: F401


def _plant_summary(driver, expect: str):
    driver.find_element("id", "plant-btn").click()
    _wait(driver, lambda d: d.execute_script("return document.body.dataset.plant") == expect, 120,
          f"the train summary ({expect})")


def test_plant_card_summarises_a_preset_and_an_uploaded_shaft_line(server, browser, tmp_path):  # noqa: F811
    """The plant card: a preset's train summary (bearings with their static loads and eccentricities, the
    stability margin at rated speed), the same for an uploaded shaft-line file, and a broken file's 4xx in
    plain words; the bearing loads shown sum to the train's weight that the API reports."""
    _open(browser, server)
    _wait(browser, lambda d: len(Select(d.find_element("id", "plant-preset")).options) >= 4, 30, "the presets")
    Select(browser.find_element("id", "plant-preset")).select_by_value("gen200_2pole")
    _plant_summary(browser, "done")
    rows = browser.find_elements("css selector", "#plant-bearings tbody tr")
    assert [r.get_attribute("data-bearing") for r in rows] == ["B1", "B2", "B3", "B4"]
    shown_kn = [float(r.find_elements("tag name", "td")[3].text) for r in rows]
    ecc = [float(r.find_elements("tag name", "td")[5].text) for r in rows]
    assert all(0 <= e < 1 for e in ecc)
    info = browser.find_element("id", "plant-info").text
    assert "gen200_2pole" in info and "stations" in info and "generator" in info
    margin = browser.find_element("id", "plant-margin").text
    assert "3000 r/min" in margin and "log decrement" in margin and "stable" in margin
    # the weight: Σ shown loads (0.1 kN rounding each) against the rotors' masses
    status, s = _get(server + "/trains/presets")
    assert status == 200
    req = urllib.request.Request(server + "/trains/summary", data=json.dumps({"preset": "gen200_2pole"}).encode(),
                                 headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=60) as r:
        api = json.loads(r.read())
    weight_kn = sum(r["mass_kg"] for r in api["rotors"]) * 9.81 / 1e3
    assert abs(sum(shown_kn) + weight_kn) < 0.05 * 4 + 1e-6 * weight_kn
    _screenshot(browser, "plant-preset")

    # an uploaded shaft line, at a speed typed in
    browser.find_element("css selector", "input[name=plant_source][value=file]").click()
    browser.find_element("id", "plant-file").send_keys(str(ROOT / "examples" / "shaftline_200mw.toml"))
    speed = browser.find_element("id", "plant-speed")
    speed.clear()
    _plant_summary(browser, "error")   # no speed: the page asks for it before calling the service
    assert "speed" in browser.find_element("id", "plant-error").text.lower()
    speed.send_keys("3000")
    _plant_summary(browser, "done")
    assert browser.find_element("id", "plant-info").text.startswith("shaftline:")
    assert len(browser.find_elements("css selector", "#plant-bearings tbody tr")) == 4

    # a broken shaft line: the service's 422 in the page's words
    bad = tmp_path / "bad.toml"
    bad.write_text("[generator]\nsegments = [[-1.0, 0.5]]\n")
    browser.find_element("id", "plant-file").send_keys(str(bad))
    _plant_summary(browser, "error")
    err = browser.find_element("id", "plant-error").text
    assert err.startswith("The shaft train cannot be used:") and "exciter" in err
    assert not browser.find_element("id", "plant-result").is_displayed()
    _screenshot(browser, "plant-error")
