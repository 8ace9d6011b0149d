"""Hostile-file checks of ``rotordiag.features.safe_io`` (files generated here, nothing stored)."""
from __future__ import annotations

import io
import json
import math
import time

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rotordiag.features.reader import ReadLimits, read_recording
from rotordiag.features.safe_io import UnsafeFileError, check_hdf5, load_npy_bounded, loads_json_finite

MB = 1 << 20
LIMITS = dict(max_decompressed_bytes=64 * MB, max_chunk_ratio=200.0)


def h5_bytes(build) -> bytes:
    bio = io.BytesIO()
    with h5py.File(bio, "w") as f:
        build(f)
    return bio.getvalue()


def good_waveforms(f, compression="gzip"):
    rng = np.random.default_rng(0)
    data = np.cumsum(rng.normal(size=(8, 4096)), axis=1).astype(np.float32)
    f.create_dataset("waveforms", data=data, compression=compression, chunks=(1, 4096) if compression else None)
    f.attrs["sample_rate_hz"] = 4096.0
    f.create_dataset("channels/bearing", data=np.array([1, 1, 2, 2, 3, 3, 4, 4]))


# ---------------------------------------------------------------- HDF5 accepted
@pytest.mark.parametrize("compression", [None, "gzip"])
def test_ordinary_recording_passes(compression, tmp_path):
    data = h5_bytes(lambda f: good_waveforms(f, compression))
    check_hdf5(data, **LIMITS)
    path = tmp_path / "rec.h5"
    path.write_bytes(data)
    check_hdf5(path, **LIMITS)
    check_hdf5(str(path), **LIMITS)


# ---------------------------------------------------------------- HDF5 refused
def test_external_storage_pointing_at_a_server_file_is_refused(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_bytes(b"ROTORDIAG_API_KEY=hunter2\n" * 8)
    data = h5_bytes(lambda f: f.create_dataset("waveforms", shape=(1, 26), dtype="u1",
                                               external=[(str(secret), 0, 26)]))
    # the file really does read the secret when opened naively
    with h5py.File(io.BytesIO(data), "r") as f:
        assert bytes(f["waveforms"][0]).startswith(b"ROTORDIAG_API_KEY")
    with pytest.raises(UnsafeFileError, match="external storage"):
        check_hdf5(data, **LIMITS)


def test_virtual_dataset_is_refused(tmp_path):
    def build(f):
        src = f.create_dataset("src", data=np.zeros((2, 16)))
        layout = h5py.VirtualLayout(shape=(2, 16), dtype="f8")
        layout[:] = h5py.VirtualSource(src)
        f.create_virtual_dataset("waveforms", layout)
    with pytest.raises(UnsafeFileError, match="virtual dataset"):
        check_hdf5(h5_bytes(build), **LIMITS)


def test_self_referencing_virtual_dataset_is_refused_without_crashing():
    # the construct that overflowed h5py's stack in the server process: a VDS mapping itself
    def build(f):
        layout = h5py.VirtualLayout(shape=(1, 8), dtype="f8")
        layout[:] = h5py.VirtualSource(".", "waveforms", shape=(1, 8))
        f.create_virtual_dataset("waveforms", layout)
    with pytest.raises(UnsafeFileError, match="virtual dataset"):
        check_hdf5(h5_bytes(build), **LIMITS)


def test_soft_and_external_links_are_refused():
    def soft(f):
        good_waveforms(f)
        f["alias"] = h5py.SoftLink("/waveforms")

    def external(f):
        f["waveforms"] = h5py.ExternalLink("/etc/passwd", "/x")
    with pytest.raises(UnsafeFileError, match="soft link"):
        check_hdf5(h5_bytes(soft), **LIMITS)
    with pytest.raises(UnsafeFileError, match="external link"):
        check_hdf5(h5_bytes(external), **LIMITS)


def test_filters_other_than_gzip_shuffle_fletcher32_are_refused():
    data = h5_bytes(lambda f: good_waveforms(f, "lzf"))  # filter id 32000: not a built-in HDF5 filter
    with pytest.raises(UnsafeFileError, match="filter id 32000"):
        check_hdf5(data, **LIMITS)


def test_gzip_bomb_is_refused_before_inflating():
    # shape (1, 1), one chunk of 16 MiB of zeros that gzips to ~16 kB
    def build(f):
        ds = f.create_dataset("waveforms", shape=(1, 1), maxshape=(None, None), chunks=(1, 2 * MB),
                              dtype="f8", compression="gzip", compression_opts=9)
        ds.resize((1, 2 * MB))
        ds[0, :] = 0.0
        ds.resize((1, 1))
    data = h5_bytes(build)
    assert len(data) < 100_000
    with pytest.raises(UnsafeFileError, match="ratio"):
        check_hdf5(data, max_decompressed_bytes=64 * MB, max_chunk_ratio=200.0)
    with pytest.raises(UnsafeFileError, match="chunks of shape"):
        check_hdf5(data, max_decompressed_bytes=1 * MB, max_chunk_ratio=1e9)


def test_declared_size_over_the_bound_is_refused():
    data = h5_bytes(lambda f: f.create_dataset("waveforms", shape=(8, 10**9), dtype="f8"))  # never written
    with pytest.raises(UnsafeFileError, match="decompress to more than"):
        check_hdf5(data, **LIMITS)


def test_hard_link_cycle_terminates():
    def build(f):
        good_waveforms(f)
        f["loop"] = f["/"]  # a hard link from a group to the root
    check_hdf5(h5_bytes(build), **LIMITS)


@pytest.mark.parametrize("body", [b"", b"not hdf5", b"\x89HDF\r\n\x1a\n" + b"\x00" * 64])
def test_not_hdf5_or_corrupt(body):
    with pytest.raises(UnsafeFileError):
        check_hdf5(body, **LIMITS)


# ---------------------------------------------------------------- NPY
def npy(arr) -> bytes:
    bio = io.BytesIO()
    np.save(bio, arr)
    return bio.getvalue()


def test_npy_roundtrip_and_fortran_order():
    a = np.arange(24, dtype=np.float32).reshape(3, 8)
    out = load_npy_bounded(npy(a), max_bytes=1 * MB)
    np.testing.assert_array_equal(out, a)
    assert out.flags.writeable
    np.testing.assert_array_equal(load_npy_bounded(npy(np.asfortranarray(a)), max_bytes=1 * MB), a)


def test_npy_huge_declared_shape_is_refused_without_allocating():
    header = npy(np.zeros((8, 10), np.float64))
    forged = header.replace(b"(8, 10)", b"(8, 100000000000)")
    with pytest.raises(UnsafeFileError, match="more than the"):
        load_npy_bounded(forged, max_bytes=64 * MB)
    with pytest.raises(UnsafeFileError, match="truncated"):
        load_npy_bounded(forged, max_bytes=10**13)


def test_npy_header_that_breaks_numpys_tokenizer_is_refused():
    # found by test_fuzz_npy_parser: a header cut short and followed by "(" makes numpy's
    # old-header fallback raise tokenize.TokenError, which is not a ValueError
    body = npy(np.arange(16, dtype=np.float64).reshape(2, 8))
    with pytest.raises(UnsafeFileError, match="NPY header"):
        load_npy_bounded(body[:127] + b"(", max_bytes=MB)


def test_npy_length_mismatch_and_objects_are_refused():
    body = npy(np.zeros((2, 4)))
    with pytest.raises(UnsafeFileError, match="truncated"):
        load_npy_bounded(body[:-1], max_bytes=MB)
    with pytest.raises(UnsafeFileError, match="extra bytes"):
        load_npy_bounded(body + b"\x00", max_bytes=MB)
    with pytest.raises(UnsafeFileError, match="not accepted"):
        load_npy_bounded(npy(np.array([{"a": 1}], dtype=object)), max_bytes=MB)
    with pytest.raises(UnsafeFileError, match="magic"):
        load_npy_bounded(b"PK\x03\x04", max_bytes=MB)


# ---------------------------------------------------------------- JSON
@pytest.mark.parametrize("text", ['{"a": NaN}', '{"a": Infinity}', '[-Infinity]', '{"a": 1e999}',
                                  '[-1e400]', "[" + "9" * 400 + "]"])
def test_non_finite_json_is_refused(text):
    with pytest.raises(UnsafeFileError, match="finite"):
        loads_json_finite(text)


def test_json_finite_values_pass_and_deep_nesting_is_refused():
    assert loads_json_finite(b'{"a": [1, 2.5, -1e300], "b": null}') == {"a": [1, 2.5, -1e300], "b": None}
    with pytest.raises(UnsafeFileError, match="nested"):
        loads_json_finite("[" * 100_000 + "]" * 100_000)
    with pytest.raises(json.JSONDecodeError):
        loads_json_finite("{")


# ---------------------------------------------------------------- fuzz: no crash, only UnsafeFileError/ValueError
FUZZ_EXAMPLES = 300


@settings(max_examples=FUZZ_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=512), st.integers(0, 400))
def test_fuzz_npy_parser(tail, cut):
    body = npy(np.arange(16, dtype=np.float64).reshape(2, 8))
    mutated = body[:cut] + tail
    try:
        out = load_npy_bounded(mutated, max_bytes=MB)
    except ValueError:
        return
    assert out.nbytes <= MB


_H5 = h5_bytes(lambda f: good_waveforms(f, "gzip"))
_FUZZ_LIMITS = ReadLimits(max_hdf5_bytes=64 * MB, hdf5_memory_bytes=256 * MB, hdf5_timeout_s=20.0)


_FLIPS = st.lists(st.tuples(st.integers(0, len(_H5) - 1), st.integers(0, 255)), min_size=1, max_size=8)
#: each example starts a sandboxed reader process (~0.13 s); the slow run tries ten times as many
FUZZ_HDF5_EXAMPLES = 100


def _read_flipped_hdf5(flips: list[tuple[int, int]]) -> None:
    """Byte-flipped HDF5 through the production path: structure check and decoding in the sandbox.

    The HDF5 library itself can loop while allocating on some flipped files (seen: ~250 MiB/s
    inside ``H5Oget_info`` until the machine's memory was gone, when this fuzz ran the check
    in the test process); in the sandbox such a file is a ``ValueError`` within the limits.
    """
    data = bytearray(_H5)
    for pos, val in flips:
        data[pos] = val
    t0 = time.monotonic()
    try:
        read_recording(bytes(data), filename="fuzz.h5", limits=_FUZZ_LIMITS)
    except ValueError:
        pass
    assert time.monotonic() - t0 < _FUZZ_LIMITS.hdf5_timeout_s + 10


@settings(max_examples=FUZZ_HDF5_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_FLIPS)
def test_fuzz_hdf5_reader(flips):
    _read_flipped_hdf5(flips)


@pytest.mark.slow
@settings(max_examples=10 * FUZZ_HDF5_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_FLIPS)
def test_fuzz_hdf5_reader_long(flips):
    _read_flipped_hdf5(flips)


def _all_finite(obj) -> bool:
    if isinstance(obj, float):
        return math.isfinite(obj)
    if isinstance(obj, list):
        return all(_all_finite(v) for v in obj)
    if isinstance(obj, dict):
        return all(_all_finite(v) for v in obj.values())
    return True


@settings(max_examples=FUZZ_EXAMPLES, deadline=None)
@given(st.recursive(st.none() | st.booleans() | st.floats() | st.integers() | st.text(max_size=8),
                    lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=4), c, max_size=4),
                    max_leaves=20))
def test_fuzz_json_never_returns_non_finite(value):
    text = json.dumps(value)  # allow_nan: NaN/Infinity appear in the text as values
    try:
        out = loads_json_finite(text)
    except UnsafeFileError:
        assert not _all_finite(value)
        return
    assert _all_finite(value) and out == value


_UNSAFE_OR_NOT = [b'{"a": [1.5, -2e-7, 3]}', b'[NaN]', b'{"x": -Infinity}', b'[1e999]', b'[1E+0400]', b'[2e308]',
                  b'[1e308]', b'[1e0099]', b'[' + b'9' * 310 + b']', b'[' + b'9' * 299 + b']', b'["NaN as text"]',
                  b'["e999"]', b'[1,2', b'\xff\xfe[\x001\x00]\x00', b'[\xff]', b'[' * 70 + b']' * 70,
                  '{"a": [1.0, 2.0]}'.encode("utf-16"), b'{"plant": "caf\xc3\xa9", "v": [1e-5, 2.5]}']


@pytest.mark.parametrize("text", _UNSAFE_OR_NOT)
def test_check_json_finite_refuses_what_loads_json_finite_refuses(text):
    """The check without decoding (``check_json_finite``, before pydantic decodes a body) refuses exactly the texts
    the decoding check refuses, with the same message; malformed JSON passes both (its decoder reports it)."""
    from rotordiag.features.safe_io import check_json_finite

    try:
        loads_json_finite(text)
        expected = None
    except UnsafeFileError as exc:
        expected = str(exc)
    except ValueError:
        expected = None
    if expected is None:
        check_json_finite(text)
    else:
        with pytest.raises(UnsafeFileError) as got:
            check_json_finite(text)
        assert str(got.value) == expected


@given(st.text(alphabet="0123456789eE+-.,[] ", max_size=400))
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_overflow_spelling_test_agrees_with_the_regular_expression(text):
    """``_may_overflow`` (substring searches on the marked text) finds every spelling the plain regular
    expression ``[eE][+]?0*[1-9][0-9]{2,}|[0-9]{300}`` finds."""
    import re

    from rotordiag.features.safe_io import _may_overflow

    raw = text.encode()
    if re.search(rb"[eE][+]?0*[1-9][0-9]{2,}|[0-9]{300}", raw):
        assert _may_overflow(raw)
    long = raw + b"," + b"7" * 300
    assert _may_overflow(long)


@given(st.text(alphabet='[]{},1 "', max_size=200))
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_innermost_arrays_found_by_find_are_the_regular_expressions_matches(text):
    """``count_json_values``' innermost arrays, found bracket to bracket with ``bytes.find``, are the matches of
    ``\\[[^\\[\\]]*\\]``; text with more brackets than ``_FEW_BRACKETS`` takes the regular expression."""
    import re

    from rotordiag.features.safe_io import _FEW_BRACKETS, _inner_arrays

    for raw in (text.encode(), text.encode() + b"[" * (_FEW_BRACKETS + 1) + b"]"):
        assert _inner_arrays(raw) == [(m.start(), m.end()) for m in re.finditer(rb"\[[^\[\]]*\]", raw)]
