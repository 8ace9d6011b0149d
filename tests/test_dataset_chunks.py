"""Waveform chunks compressed in the worker and stored with write_direct_chunk; submission order."""
from __future__ import annotations

import zlib

import h5py
import numpy as np
import pytest

from rotordiag.simulator.dataset.design import build_design
from rotordiag.simulator.dataset.generate import generate, submission_order
from rotordiag.simulator.dataset.measurement import MeasurementSettings
from rotordiag.simulator.dataset.spec import load_spec
from rotordiag.simulator.dataset.store import (
    DatasetWriter,
    EncodedChunk,
    _takes_encoded_chunks,
    create_file,
    decode_waveform_chunk,
    encode_waveform_chunk,
)
from rotordiag.simulator.dataset.worker import SampleTask, SimulationSettings, run_sample, run_sample_encoded

from .dataset_support import write_spec


def _awkward_waveforms(shape=(8, 300)) -> np.ndarray:
    rng = np.random.default_rng(3)
    t = np.arange(shape[1]) / 1024.0
    w = (40 * np.sin(2 * np.pi * 31 * t)[None, :] + rng.normal(size=shape)).astype(np.float32)
    w[0, :5] = np.nan           # stopped simulation
    w[1, 7] = np.inf
    w[2, 9] = -0.0
    w[3, 11] = np.float32(1e-42)  # subnormal
    return w


def test_encode_decode_is_bit_exact():
    w = _awkward_waveforms()
    c = encode_waveform_chunk(w)
    assert isinstance(c, EncodedChunk) and c.shape == w.shape and len(c.data) < w.nbytes
    back = decode_waveform_chunk(c)
    assert back.dtype == np.float32 and back.tobytes() == w.tobytes()
    assert encode_waveform_chunk(np.full((8, 300), np.nan, np.float32)).decode().shape == (8, 300)


def _two_datasets(path, tail, compression="gzip"):
    opts = 4 if compression == "gzip" else None
    with h5py.File(path, "w", libver="latest") as f:
        for name in ("normal", "direct"):
            f.create_dataset(name, shape=(3, *tail), dtype="f4", chunks=(1, *tail), shuffle=True,
                             compression=compression, compression_opts=opts, fillvalue=np.nan)


def test_direct_chunk_equals_the_normal_write_and_plain_h5py_reads_it(tmp_path):
    w = _awkward_waveforms()
    path = tmp_path / "c.h5"
    _two_datasets(path, w.shape)
    with h5py.File(path, "r+", libver="latest") as f:
        f["normal"][1] = w                                       # HDF5 runs its own shuffle + deflate
        assert _takes_encoded_chunks(f["direct"])
        f["direct"].id.write_direct_chunk((1, 0, 0), encode_waveform_chunk(w).data, 0)
    with h5py.File(path, "r") as f:                              # plain h5py, no rotordiag code
        assert f["direct"][1].tobytes() == f["normal"][1].tobytes() == w.tobytes()
        assert np.isnan(f["direct"][0]).all() and np.isnan(f["direct"][2]).all()  # other rows: fill value
        mask_n, raw_n = f["normal"].id.read_direct_chunk((1, 0, 0))
        mask_d, raw_d = f["direct"].id.read_direct_chunk((1, 0, 0))
    assert mask_n == mask_d == 0
    # the same filtered payload; the deflate bytes themselves agree when HDF5's zlib is Python's
    assert zlib.decompress(raw_n) == zlib.decompress(raw_d)


def _writer_on(path):
    class _NoLock:
        def release(self):
            pass

    f = h5py.File(path, "r+", libver="latest")
    return DatasetWriter(path, f, _NoLock(), False, False)


def _create(path, compression):
    L = {"waveforms": ((8, 300), "f4"), "done": ((), "u1")}
    create_file(path, 3, L, [(1, 45.0)] * 8, {"format": "rotordiag-dataset"}, {}, compression=compression)


@pytest.mark.parametrize("compression, direct", [("gzip", True), ("lzf", False)])
def test_writer_stores_encoded_chunks_or_falls_back(tmp_path, compression, direct):
    w = _awkward_waveforms()
    path = tmp_path / f"{compression}.h5"
    _create(path, compression)
    writer = _writer_on(path)
    assert writer._direct_waveforms is direct   # lzf: not the pipeline the chunk was encoded for
    writer.write_sample(1, {"waveforms": encode_waveform_chunk(w)})
    writer.close()
    with h5py.File(path, "r") as f:
        assert f["waveforms"][1].tobytes() == w.tobytes()
        assert f["done"][...].tolist() == [0, 1, 0]
        assert f["waveforms"].compression == compression


def test_generated_file_holds_the_workers_arrays(tmp_path):
    spec = write_spec(tmp_path / "spec.toml", n_samples=4)
    out = tmp_path / "o.h5"
    generate(spec, out, n_workers=0, progress=False)
    r = load_spec(spec)
    d, sim, meas = build_design(r), SimulationSettings.from_spec(r.spec), MeasurementSettings.from_spec(r.spec)
    with h5py.File(out, "r") as f:
        for i in (0, 3):
            task = SampleTask(d[i], sim, meas)
            plain = run_sample(task).waveforms_um
            encoded = run_sample_encoded(task).waveforms_um
            assert isinstance(encoded, EncodedChunk)
            assert f["waveforms"][i].tobytes() == plain.tobytes() == encoded.decode().tobytes()


def test_submission_order_puts_fast_shafts_first_within_blocks(tmp_path):
    spec = write_spec(tmp_path / "spec.toml", n_samples=32)
    d = build_design(load_spec(spec))
    todo = np.array([i for i in range(32) if i % 5 != 0])   # a resumed run: some samples already done
    order = submission_order(d, todo, block=8)
    assert sorted(order.tolist()) == todo.tolist()
    for b in range(0, len(todo), 8):
        blk = order[b:b + 8]
        assert set(blk.tolist()) == set(todo[b:b + 8].tolist())  # blocks keep design order between them
        speeds = [d[int(i)].speed_rpm for i in blk]
        assert speeds == sorted(speeds, reverse=True)
    assert submission_order(d, np.array([], dtype=np.int64)).size == 0
