"""Bad start-ups through every door (issue 46): a run-up that turns back, a keyphasor that drops out mid-run and a
10⁸-sample file are refused with a message saying what is wrong and what to do — by `rotordiag plots`, by `rotordiag
report --startup` and `--baseline-startup`, and by the service's POST /ui/transient-plots (POST
/assets/{id}/startup: tests/test_service_startup.py) — and nothing is written."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from rotordiag.cli import app
from tests.test_features_transient import FS, LAYOUT, _huge_npy, _ramp, _synthetic

#: each bad file and the start of what every door must say about it
EXPECTED = {"reverses": "the speed reverses at t = ", "dropout": "keyphasor drops out: the pulse interval at t = ",
            "huge": "(8, 100000000)"}


def _pulses(t: np.ndarray, marks: np.ndarray) -> np.ndarray:
    sig = np.zeros(t.size)
    for tk in marks:
        sig[(t >= tk) & (t < tk + 0.004)] = -1.0
    return sig


@pytest.fixture(scope="module")
def bad_files(tmp_path_factory) -> dict[str, Path]:
    from rotordiag.simulator.cli import write_probes

    d = tmp_path_factory.mktemp("bad")
    t = np.arange(int(12 * FS)) / FS
    rpm = np.where(t < 6, 900 + 100 * t, 1500 - 100 * (t - 6))            # up for 6 s, then back down
    th = 2 * np.pi * np.cumsum(rpm / 60.0) / FS
    marks = np.interp(2 * np.pi * np.arange(1, int(th[-1] / (2 * np.pi))), th, t)
    w = np.array([10 * np.cos(th - math.radians(a)) for _, a in LAYOUT])
    write_probes(d / "reverses.csv", w, LAYOUT, FS, keyphasor_signal=_pulses(t, marks))
    rec, _, _ = _synthetic(dur_s=8.0, rpm1=1300.0)
    t, _, kp, _ = _ramp(900.0, 1300.0, 8.0)
    n = kp.size
    write_probes(d / "dropout.csv", np.array([c.data for c in rec.channels]), LAYOUT, FS,
                 keyphasor_signal=_pulses(t, np.r_[kp[1: n // 2], kp[n // 2 + 3:]]))   # three pulses lost
    for suffix in (".csv", ".npy"):      # the NPY: 4 probes, the keyphasor as channel 4
        write_probes(d / f"good{suffix}", np.array([c.data for c in rec.channels]), LAYOUT, FS,
                     keyphasor_signal=_pulses(t, kp[1:]))
    return {"reverses": d / "reverses.csv", "dropout": d / "dropout.csv", "huge": _huge_npy(d / "huge.npy"),
            "good": d / "good.csv", "good_npy": d / "good.npy"}


def _huge_opts(name: str) -> list[str]:
    return ["--sample-rate-hz", "25600", "--keyphasor-channel", "7"] if name == "huge" else []


@pytest.mark.parametrize("name", list(EXPECTED))
def test_plots_cli(bad_files, tmp_path, name):
    out = tmp_path / "png"
    r = CliRunner().invoke(app, ["plots", str(bad_files[name]), "--out-dir", str(out), *_huge_opts(name)])
    assert r.exit_code == 2 and EXPECTED[name] in r.output, r.output
    assert not out.exists()


@pytest.mark.parametrize("name", list(EXPECTED))
@pytest.mark.parametrize("door", ["--startup", "--baseline-startup"])
def test_report_cli(bad_files, tmp_path, name, door):
    out = tmp_path / "r.pdf"
    opts = _huge_opts(name)
    if door == "--startup":
        args = ["--startup", str(bad_files[name])]
    elif name == "huge":   # both files read with the same options: a good NPY beside the huge one
        args = ["--startup", str(bad_files["good_npy"]), "--baseline-startup", str(bad_files[name])]
        opts = ["--sample-rate-hz", str(FS), "--keyphasor-channel", "4", "--channels", "1@45,1@135,2@45,2@135"]
    else:
        args = ["--startup", str(bad_files["good"]), "--baseline-startup", str(bad_files[name])]
    r = CliRunner().invoke(app, ["report", *args, "--out", str(out), *opts])
    assert r.exit_code == 2 and EXPECTED[name] in r.output, r.output
    assert list(tmp_path.iterdir()) == []


def test_the_good_run_passes_both_report_doors(bad_files, tmp_path):
    """The control: the same synthetic run with all its pulses is read by the doors that refuse the bad ones."""
    out = tmp_path / "r.pdf"
    r = CliRunner().invoke(app, ["report", "--startup", str(bad_files["good"]), "--baseline-startup",
                                 str(bad_files["good"]), "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert out.exists() and out.with_suffix(".html").exists()


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    from rotordiag.service.main import create_app
    from tests.service_util import make_settings, shipped_or_tiny_registry

    registry = shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))
    with TestClient(create_app(make_settings(tmp_path_factory.mktemp("svc"), shipped_registry_dir=registry))) as c:
        yield c


@pytest.mark.parametrize("name", list(EXPECTED))
def test_service_transient_plots(bad_files, client, name):
    params = {"sample_rate_hz": 25600, "keyphasor_channel": 7} if name == "huge" else {}
    r = client.post("/ui/transient-plots", params=params,
                    files={"file": (bad_files[name].name, bad_files[name].read_bytes())})
    assert 400 <= r.status_code < 500 and EXPECTED[name] in r.json()["detail"], r.text
