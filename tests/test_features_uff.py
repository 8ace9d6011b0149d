"""Universal-file (UFF 58/58b) recordings through ``rotordiag.features.reader`` (pyuff underneath)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotordiag.features.examples import example_path
from rotordiag.features.reader import ReadOptions, read_recording
from rotordiag.simulator.cli import write_probes

FS = 2048.0
CHANNELS = [(2, 45.0), (2, 135.0), (3, 45.0), (3, 135.0)]


def _waves(n: int = 4096) -> np.ndarray:
    t = np.arange(n) / FS
    return np.stack([(20 + 5 * k) * np.sin(2 * np.pi * 30 * t + k) + 3 * np.sin(2 * np.pi * 60 * t) for k in range(4)])


def _rewrite(src: Path, dst: Path, edit) -> Path:
    import pyuff

    sets = [pyuff.UFF(str(src)).read_sets(i) for i in range(4)]
    edit(sets)
    dst.unlink(missing_ok=True)
    out = pyuff.UFF(str(dst))
    for d in sets:
        out.write_sets(d, mode="add")
    return dst


def test_uff_written_by_simulate_reads_back_exactly(tmp_path):
    w = _waves()
    path = tmp_path / "rec.uff"
    write_probes(path, w, CHANNELS, FS)
    res = read_recording(path)
    rec = res.recording
    assert res.format == "uff"
    assert rec.sample_rate_hz == pytest.approx(FS, rel=1e-12)
    assert [(c.bearing, c.angle_deg, c.units) for c in rec.channels] == [(b, a, "um") for b, a in CHANNELS]
    np.testing.assert_allclose(np.stack([c.data for c in rec.channels]), w, rtol=1e-12)
    # the same bytes as an upload (no name ending: the "-1 / 58" start picks the format)
    assert read_recording(path.read_bytes()).format == "uff"


def test_shipped_uff_example_gives_the_csv_examples_recording():
    uff = read_recording(example_path("whirl.uff")).recording
    csv = read_recording(example_path("whirl.csv")).recording
    assert uff.sample_rate_hz == pytest.approx(csv.sample_rate_hz, rel=1e-7)
    for a, b in zip(uff.channels, csv.channels):
        np.testing.assert_allclose(a.data, b.data, atol=6e-4)   # the CSV keeps 3 decimals


def test_channel_name_mapping_and_units_from_the_ordinate_label(tmp_path):
    src = tmp_path / "rec.uff"
    write_probes(src, _waves(), CHANNELS, FS)

    def rename(sets):
        for d, name in zip(sets, ["GEN DE X", "GEN DE Y", "EXC DE X", "EXC DE Y"]):
            d["id1"] = name
            d["ordinate_axis_units_lab"] = "mm"

    path = _rewrite(src, tmp_path / "named.uff", rename)
    with pytest.raises(ValueError, match="nor named BEARING@ANGLE"):
        read_recording(path)
    mapping = {"GEN DE X": "b2@45", "GEN DE Y": "b2@135", "EXC DE X": "b3@45", "EXC DE Y": "b3@135"}
    rec = read_recording(path, options=ReadOptions(channels=mapping)).recording
    assert [(c.bearing, c.angle_deg) for c in rec.channels] == CHANNELS
    # the file's ordinate label says mm: the channels carry it (converted to µm by the Recording)
    assert {c.units for c in rec.channels} == {"mm"}
    np.testing.assert_allclose(rec.channels[0].data, _waves()[0], rtol=1e-12)


@pytest.mark.parametrize("edit, needle", [
    (lambda s: s[1].update(x=s[1]["x"] * 2), "sample intervals differ"),
    (lambda s: s[2].update(func_type=4, abscissa_spec_data_type=18), "not a time history"),
    (lambda s: s[0].update(data=s[0]["data"][:-10], x=s[0]["x"][:-10], num_pts=s[0]["num_pts"] - 10),
     "different lengths"),
])
def test_inconsistent_records_say_what_to_fix(tmp_path, edit, needle):
    src = tmp_path / "rec.uff"
    write_probes(src, _waves(), CHANNELS, FS)
    with pytest.raises(ValueError, match=needle):
        read_recording(_rewrite(src, tmp_path / "bad.uff", edit))


def test_truncated_and_non_58_files_are_refused(tmp_path):
    src = tmp_path / "rec.uff"
    write_probes(src, _waves(), CHANNELS, FS)
    data = src.read_bytes()
    # two whole records (the file is four equal ones) are a valid two-probe file ...
    assert len(read_recording(data[: len(data) // 2], filename="cut.uff").recording.channels) == 2
    # ... a cut inside a record is not
    with pytest.raises(ValueError, match="truncated"):
        read_recording(data[: len(data) // 2 + 100], filename="cut.uff")
    only_151 = b"    -1\n   151\nmodel\n" + b"x\n" * 6 + b"    -1\n"
    with pytest.raises(ValueError, match="universal file"):
        read_recording(only_151, filename="header.unv")
