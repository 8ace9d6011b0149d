"""The report to hand on (models.report; ``rotordiag report``, ``rotordiag runup``, ``rotordiag plots``)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from rotordiag.cli import app

EXAMPLES = Path(__file__).resolve().parents[1] / "features" / "examples"


@pytest.fixture(scope="module")
def startup_csv(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("runup") / "runup.csv"
    r = CliRunner().invoke(app, ["runup", "--profile", "900:1500:6", "--misalignment", "0.3", "--out", str(out)])
    assert r.exit_code == 0, r.output
    return out


def test_runup_refuses_a_reversing_profile_and_writes_nothing(tmp_path: Path):
    out = tmp_path / "x.csv"
    r = CliRunner().invoke(app, ["runup", "--profile", "0@1000,5@2000,8@1500", "--out", str(out)])
    assert r.exit_code != 0 and "reverses at t = 5 s" in r.output
    assert list(tmp_path.iterdir()) == []


def test_plots_cli_writes_the_pngs_and_names_the_peaks(startup_csv: Path, tmp_path: Path):
    r = CliRunner().invoke(app, ["plots", str(startup_csv), "--out-dir", str(tmp_path / "png"), "--campbell"])
    assert r.exit_code == 0, r.output
    names = {p.name for p in (tmp_path / "png").iterdir()}
    assert {"bode.png", "polar.png", "campbell.png", "centreline.png", "orbits.png", "waterfall_b1.png",
            "full_spectrum_b4.png"} <= names
    assert re.search(r"1X peak b1@135: [\d.]+ µm pk-pk at 1[12]\d\d r/min", r.output)


@pytest.mark.slow
def test_report_pdf_and_html_hold_the_verdict_evidence_and_plots(startup_csv: Path, tmp_path: Path):
    out = tmp_path / "rep" / "report.pdf"
    r = CliRunner().invoke(app, ["report", str(EXAMPLES / "whirl.csv"), "--startup", str(startup_csv),
                                 "--out", str(out), "--title", "unit 3 coupling"])
    assert r.exit_code == 0, r.output
    pdf = out.read_bytes()
    assert pdf.startswith(b"%PDF")
    # text pages, then bode, polar, 4 waterfalls, 4 full spectra, centreline, orbits
    assert len(re.findall(rb"/Type /Page\b(?!s)", pdf)) >= 2 + 12
    page = out.with_suffix(".html").read_text(encoding="utf-8")
    for text in ("unit 3 coupling", "Verdict", "status:", "Reasons", "Evidence (model-independent)",
                 "Start-up / coast-down", "1X peak", "conventions: amplitude µm pk-pk"):
        assert text in page, text
    assert page.count("data:image/png;base64,") >= 10
    assert out.stat().st_mode & 0o044  # readable by others as a plain file would be


def test_report_refuses_bad_input_and_leaves_nothing(tmp_path: Path):
    out = tmp_path / "report.pdf"
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,b1@45,b1@135\n0,1,2\n")
    r = CliRunner().invoke(app, ["report", str(bad), "--out", str(out)])
    assert r.exit_code == 2 and "error:" in r.output
    assert not out.exists() and not out.with_suffix(".html").exists()
    r = CliRunner().invoke(app, ["report", "--out", str(out)])
    assert r.exit_code == 2 and "give an ASSET or a RECORDING" in r.output


def test_write_report_holds_what_it_is_given(tmp_path: Path):
    """The report writer alone (quick): the verdict's status, reasons and evidence, the trend, each figure a page."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rotordiag.models.report import build_report, write_report

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    verdict = {"status": "uncertain", "severity": "moderate", "misalignment": 0.31, "misalignment_interval": [0.2, 0.4],
               "speed_rpm": 2990.0, "probabilities": {"aligned": 0.1, "moderate": 0.9},
               "reasons": [{"status": "uncertain", "message": "bearing 3 & 4 <not> measured"}],
               "evidence": [{"scope": "bearing 2", "name": "2X/1X", "value": "0.8", "meaning": "strong 2X"}],
               "model_version": "v0003",
               "answered_by": {"text": "model v0003, trained on MODEL.md's plant (lumped 11-DOF); judged as "
                                       "gen600_2pole, declared by the request, a family it was NOT trained on"}}
    history = [{"created_at": "2026-01-01 10:00", "severity": "slight", "misalignment": 0.12, "misalignment_low": 0.05,
                "misalignment_high": 0.2, "speed_rpm": 3000.0, "status": "confident"},
               {"created_at": "2026-02-01 10:00", "severity": "inconclusive", "misalignment": None,
                "misalignment_low": None, "misalignment_high": None, "speed_rpm": None, "status": "inconclusive"}]
    content = build_report(title="T <1>", asset_id="G3", recordings=[{"file": "a.csv", "role": "steady",
                                                                        "format": "csv", "notes": []}],
                           verdict=verdict, history=history, figures={"bode": fig})
    pdf, page = write_report(content, tmp_path / "r.pdf", tmp_path / "r.html")
    plt.close(fig)
    html = page.read_text(encoding="utf-8")
    assert "T &lt;1&gt;" in html and "&lt;not&gt;" in html          # escaped, not injected
    assert "WHAT TO DO (before acting): confirm before acting: the model reads moderate misalignment" in html
    for text in ("status: uncertain", "severity: moderate", "0.310 (interval 0.200 – 0.400)", "bearing 2 · 2X/1X",
                 "Trend (2 stored diagnoses)", "2026-02-01 10:00: inconclusive",
                 "answered by: model v0003, trained on MODEL.md&#x27;s plant (lumped 11-DOF); judged as gen600_2pole, "
                 "declared by the request, a family it was NOT trained on"):
        assert text in html, text
    assert html.count("data:image/png;base64,") == 2                 # trend + bode
    n_pages = len(re.findall(rb"/Type /Page\b(?!s)", pdf.read_bytes()))
    assert n_pages == 1 + 2                                           # one text page, trend, bode
