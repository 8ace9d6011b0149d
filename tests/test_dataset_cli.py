"""`rotordiag dataset generate | info | merge | repair`: clean messages, summaries, merging."""
from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.simulator.dataset.generate import generate

from .dataset_support import write_spec

runner = CliRunner()


@pytest.fixture(scope="module")
def two_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    a = generate(write_spec(d / "a.toml", n_samples=4, seed=1), d / "a.h5", n_workers=0, progress=False)
    b = generate(write_spec(d / "b.toml", n_samples=3, seed=2), d / "b.h5", n_workers=0, progress=False)
    return d, a.path, b.path


def _clean_failure(result, fragment):
    assert result.exit_code == 2, result.output
    assert fragment in result.output
    assert "Traceback" not in result.output


def test_invalid_spec_is_a_clean_error(tmp_path):
    spec = write_spec(tmp_path / "s.toml")
    spec.write_text(spec.read_text().replace("max = 2100", "max = 9000"))
    r = runner.invoke(app, ["dataset", "generate", str(spec), "--out", str(tmp_path / "o.h5"), "--workers", "0"])
    _clean_failure(r, "speed_rpm must lie in [100, 6000]")
    assert not (tmp_path / "o.h5").exists()


def test_missing_spec_and_bad_options(tmp_path):
    r = runner.invoke(app, ["dataset", "generate", str(tmp_path / "none.toml"), "--out", str(tmp_path / "o.h5")])
    _clean_failure(r, "does not exist")
    spec = write_spec(tmp_path / "s.toml")
    r = runner.invoke(app, ["dataset", "generate", str(spec), "--out", str(tmp_path / "o.h5"),
                            "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"])
    _clean_failure(r, "either --workers or --scheduler")
    r = runner.invoke(app, ["dataset", "generate", str(spec), "--out", str(tmp_path / "no" / "o.h5"), "--workers", "0"])
    _clean_failure(r, "output folder")


def test_other_spec_on_existing_output_is_refused(two_files):
    d, a, _ = two_files
    r = runner.invoke(app, ["dataset", "generate", str(d / "b.toml"), "--out", str(a), "--workers", "0"])
    _clean_failure(r, "was generated from a different spec")


def test_generate_and_info(tmp_path):
    spec = write_spec(tmp_path / "s.toml", n_samples=3)
    out = tmp_path / "o.h5"
    r = runner.invoke(app, ["dataset", "generate", str(spec), "--out", str(out), "--workers", "0", "--no-progress"])
    assert r.exit_code == 0, r.output
    assert "created; 3 samples computed, 3/3 done" in r.output
    r = runner.invoke(app, ["dataset", "info", str(out)])
    assert r.exit_code == 0, r.output
    assert "3/3 done" in r.output and "b1@45°" in r.output and "status      ok 3" in r.output
    assert "samples are steady runs, one speed each" in r.output
    js = json.loads(runner.invoke(app, ["dataset", "info", str(out), "--json"]).output)
    with h5py.File(out, "r") as f:
        sev = f["labels/severity"][...]
        speeds = f["parameters/speed_rpm"][...]
    assert js["n_done"] == 3 and js["status_counts"] == {"ok": 3}
    assert sum(js["severity_counts"].values()) == 3
    assert js["severity_counts"]["severe"] == int(np.count_nonzero(sev == 3))
    assert js["parameter_ranges"]["speed_rpm"] == [speeds.min(), speeds.max()]
    assert js["n_plants"] == 3 and js["sample_kind"] == "steady"


def test_info_of_a_non_dataset(tmp_path):
    with h5py.File(tmp_path / "x.h5", "w") as f:
        f["a"] = 1
    _clean_failure(runner.invoke(app, ["dataset", "info", str(tmp_path / "x.h5")]), "not a rotordiag dataset")


def test_merge_joins_finished_samples_and_records_sources(two_files, tmp_path):
    d, a, b = two_files
    out = tmp_path / "m.h5"
    r = runner.invoke(app, ["dataset", "merge", str(a), str(b), "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "7 samples from 2 source specs" in r.output
    with h5py.File(out, "r") as m, h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        assert m["waveforms"].shape == (7, 8, 164)
        assert np.array_equal(m["waveforms"][:4], fa["waveforms"][...])
        assert np.array_equal(m["waveforms"][4:], fb["waveforms"][...])
        assert np.array_equal(m["parameters/plant/generator_mass_kg"][4:], fb["parameters/plant/generator_mass_kg"][...])
        assert m["source"][...].tolist() == [0, 0, 0, 0, 1, 1, 1]
        sources = json.loads(m.attrs["sources_json"])
        assert [s["spec_hash"] for s in sources] == [fa.attrs["spec_hash"], fb.attrs["spec_hash"]]
        assert m.attrs["merged"]
    # a merged file is not resumable, and the same spec twice is refused
    r = runner.invoke(app, ["dataset", "generate", str(d / "a.toml"), "--out", str(out), "--workers", "0"])
    _clean_failure(r, "merged dataset and cannot be resumed")
    r = runner.invoke(app, ["dataset", "merge", str(out), str(a), "--out", str(tmp_path / "m2.h5")])
    _clean_failure(r, "come from the same spec")
    # merging a merged file with a new spec keeps the source indices straight
    c = generate(write_spec(tmp_path / "c.toml", n_samples=2, seed=3), tmp_path / "c.h5", n_workers=0, progress=False)
    r = runner.invoke(app, ["dataset", "merge", str(out), str(c.path), "--out", str(tmp_path / "m3.h5")])
    assert r.exit_code == 0, r.output
    with h5py.File(tmp_path / "m3.h5", "r") as m:
        assert m["source"][...].tolist() == [0, 0, 0, 0, 1, 1, 1, 2, 2]


def test_merge_refuses_another_family(two_files, tmp_path):
    d, a, _ = two_files
    other = generate(write_spec(tmp_path / "o.toml", n_samples=2, seed=9, sample_rate_hz=2048.0),
                     tmp_path / "o.h5", n_workers=0, progress=False)
    r = runner.invoke(app, ["dataset", "merge", str(a), str(other.path), "--out", str(tmp_path / "m.h5")])
    _clean_failure(r, "not of the same family")
    assert not (tmp_path / "m.h5").exists()
    r = runner.invoke(app, ["dataset", "merge", str(a), "--out", str(tmp_path / "m.h5")])
    _clean_failure(r, "at least two input files")


def test_repair_of_a_clean_file_does_nothing(two_files):
    _, a, _ = two_files
    r = runner.invoke(app, ["dataset", "repair", str(a)])
    assert r.exit_code == 0 and "nothing to repair; 4 finished samples" in r.output


def test_reader_decodes_labels_and_streams_waveforms(two_files, tmp_path):
    from rotordiag.simulator.dataset import DatasetReader

    _, a, b = two_files
    merged = tmp_path / "m.h5"
    runner.invoke(app, ["dataset", "merge", str(a), str(b), "--out", str(merged)])
    with DatasetReader(a) as ds, h5py.File(a, "r") as f:
        lab = ds.labels()
        assert len(ds) == 4 and lab["index"].tolist() == [0, 1, 2, 3]
        delta = f["parameters/misalignment"][...]
        assert np.array_equal(lab["misalignment"], delta)
        expected = np.select([delta < 0.05, delta < 0.15, delta < 0.35], ["aligned", "slight", "moderate"], "severe")
        assert lab["severity_name"].tolist() == expected.tolist()
        assert set(lab["status"]) == {"ok"}
        codes = f["parameters/simulated_mechanism"][...]
        assert lab["mechanism"].tolist() == [["pin", "rigid", "aligned"][c] for c in codes]
        assert all(len(p) == 16 for p in lab["plant_id"])
        assert ds.channels[0] == (1, 45.0) and ds.sample_rate_hz == 1024.0
        rows = dict(ds.iter_waveforms())
        assert sorted(rows) == [0, 1, 2, 3] and np.array_equal(rows[2], f["waveforms"][2])
        assert np.array_equal(ds.parameters("parameters/plant/asymmetry"), f["parameters/plant/asymmetry"][...])
    with DatasetReader(merged) as ds:
        assert ds.labels()["source"].tolist() == [0, 0, 0, 0, 1, 1, 1]


def test_info_on_a_file_missing_part_of_the_layout_is_a_clean_error(two_files, tmp_path):
    """A file from older code (here: without resume_log) gets a message, not a traceback."""
    import shutil

    _, a, _ = two_files
    old = tmp_path / "old.h5"
    shutil.copy(a, old)
    with h5py.File(old, "r+") as f:
        del f["resume_log"]
    _clean_failure(runner.invoke(app, ["dataset", "info", str(old)]), "regenerate it")
