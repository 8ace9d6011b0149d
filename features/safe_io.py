"""Checks that make untrusted recording files safe to decode.

Three pure primitives, used by every reader of files that come from outside
(service uploads, ``rotordiag diagnose FILE``):

``check_hdf5``
    Walks an HDF5 file's structure with h5py's low-level API *without reading
    any dataset values* and refuses what could read other files, crash the
    HDF5 library or blow up memory: external storage, virtual datasets,
    soft/external/user-defined links, filters other than the built-in
    deflate/shuffle/fletcher32, and datasets or chunks whose decompressed size
    or compression ratio exceed the caller's bounds.  The decompressed size is
    computed from the declared shapes and chunk index, so it is bounded
    before a single byte is inflated.
``load_npy_bounded``
    Reads an NPY header, checks the declared shape x dtype against the
    caller's bound *and* against the body length, then views the body;
    nothing is allocated from a size the file merely claims.
``loads_json_finite``
    ``json.loads`` that refuses ``NaN``, ``Infinity`` and numbers that
    overflow to infinity (``1e999``), with a message that says what to send.

Every refusal is an :class:`UnsafeFileError` (a ``ValueError``) whose message
says what is wrong with the file and what to send instead.
"""
from __future__ import annotations

import io
import json
import math
import re
import tokenize
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["UnsafeFileError", "check_hdf5", "load_npy_bounded", "loads_json_finite", "check_json_finite",
           "count_json_values",
           "ALLOWED_HDF5_FILTERS", "MAX_HDF5_OBJECTS", "MAX_HDF5_CHUNKS"]

#: HDF5 filter ids an upload may use: deflate (gzip), shuffle, fletcher32.
ALLOWED_HDF5_FILTERS = {1: "deflate", 2: "shuffle", 3: "fletcher32"}
#: At most this many groups + datasets are walked (a recording needs a handful).
MAX_HDF5_OBJECTS = 1_000
#: At most this many allocated chunks over all datasets (each one's index entry is inspected).
MAX_HDF5_CHUNKS = 200_000

#: What h5py raises on corrupt files (besides the HDF5 errors, which are OSError/KeyError/ValueError).
_H5_ERRORS = (OSError, ValueError, KeyError, TypeError, RuntimeError, OverflowError, IndexError, SystemError)
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
_NPY_MAGIC = b"\x93NUMPY"


class UnsafeFileError(ValueError):
    """A file refused before decoding; the message says why and what to send instead."""


# --------------------------------------------------------------------------- HDF5
def check_hdf5(source: bytes | str | Path, *, max_decompressed_bytes: int, max_chunk_ratio: float,
               max_chunks: int = MAX_HDF5_CHUNKS) -> None:
    """Refuse an HDF5 file whose decoding could read other files, crash or exhaust memory.

    Parameters
    ----------
    source : bytes or str or Path
        The file's bytes (an upload) or its path.
    max_decompressed_bytes : int
        Bound on the in-memory size (shape x itemsize) of all datasets together,
        and so on every single chunk.
    max_chunk_ratio : float
        Bound on every allocated chunk's decompressed/stored size ratio
        (gzip reaches ~1000 on constant data; real waveforms ~1-5).
    max_chunks : int
        Bound on the chunks over all datasets, checked on the chunk grid (shape / chunk shape) before
        the chunk index is read, so a file of many tiny chunks costs no per-chunk call.

    Raises
    ------
    UnsafeFileError
        Not HDF5, unreadable, or any refused construct (see the module docstring).
    """
    if max_decompressed_bytes <= 0 or not max_chunk_ratio > 0:
        raise ValueError("max_decompressed_bytes and max_chunk_ratio must be positive")
    import h5py

    if isinstance(source, (bytes, bytearray, memoryview)):
        head = bytes(source[:8])
        opener: Any = io.BytesIO(bytes(source))
    else:
        path = Path(source)
        with open(path, "rb") as fh:
            head = fh.read(8)
        opener = str(path)
    if head != _HDF5_SIGNATURE:
        raise UnsafeFileError("not an HDF5 file (it must start with the HDF5 signature \\x89HDF\\r\\n\\x1a\\n)")
    try:
        f = h5py.File(opener, "r")
    except _H5_ERRORS as exc:
        raise UnsafeFileError(f"cannot open the HDF5 file (truncated or corrupt?): {exc}") from None
    try:
        _Walk(max_decompressed_bytes, max_chunk_ratio, max_chunks).group(f, "/")
    except UnsafeFileError:
        raise
    except _H5_ERRORS as exc:
        raise UnsafeFileError(f"cannot inspect the HDF5 file's structure (corrupt?): {exc}") from None
    finally:
        f.close()


class _Walk:
    """Depth-first walk over hard links only; state: objects seen, bytes and chunks counted."""

    def __init__(self, max_bytes: int, max_ratio: float, max_chunks: int = MAX_HDF5_CHUNKS) -> None:
        self.max_bytes = max_bytes
        self.max_ratio = max_ratio
        self.max_chunks = max_chunks
        self.seen: set[int] = set()
        self.total_bytes = 0
        self.total_chunks = 0

    def _visit_once(self, obj: Any, path: str) -> bool:
        import h5py

        addr = h5py.h5o.get_info(obj.id).addr
        if addr in self.seen:
            return False
        self.seen.add(addr)
        if len(self.seen) > MAX_HDF5_OBJECTS:
            raise UnsafeFileError(f"the HDF5 file holds more than {MAX_HDF5_OBJECTS} groups/datasets; "
                                  "send a file with just the recording")
        return True

    def group(self, grp: Any, path: str) -> None:
        import h5py

        if not self._visit_once(grp, path):
            return
        for name in list(grp.keys()):  # H5Literate: names only, links not followed
            child_path = f"{path.rstrip('/')}/{name}"
            try:
                link = grp.get(name, getlink=True)
            except (TypeError, KeyError, OSError):
                link = None
            if isinstance(link, h5py.SoftLink):
                raise UnsafeFileError(f"the HDF5 file has a soft link {child_path!r} -> {link.path!r}; "
                                      "links are refused, store the dataset itself")
            if isinstance(link, h5py.ExternalLink):
                raise UnsafeFileError(f"the HDF5 file has an external link {child_path!r} to another file; "
                                      "links to other files are refused, store the data in the upload")
            if not isinstance(link, h5py.HardLink):
                raise UnsafeFileError(f"the HDF5 file has a user-defined link {child_path!r}; it is refused")
            child = grp[name]
            if isinstance(child, h5py.Group):
                self.group(child, child_path)
            elif isinstance(child, h5py.Dataset):
                if self._visit_once(child, child_path):
                    self.dataset(child, child_path)
            # committed datatypes hold no data: nothing to check

    def dataset(self, ds: Any, path: str) -> None:
        import h5py

        dcpl = ds.id.get_create_plist()
        layout = dcpl.get_layout()
        if layout == h5py.h5d.VIRTUAL:
            raise UnsafeFileError(f"HDF5 dataset {path!r} is a virtual dataset (it maps other datasets/files); "
                                  "virtual datasets are refused, store the values themselves")
        if dcpl.get_external_count() > 0:
            raise UnsafeFileError(f"HDF5 dataset {path!r} keeps its values in external files; external storage "
                                  "is refused, store the values inside the HDF5 file")
        for i in range(dcpl.get_nfilters()):
            fid = dcpl.get_filter(i)[0]
            if fid not in ALLOWED_HDF5_FILTERS:
                raise UnsafeFileError(f"HDF5 dataset {path!r} uses filter id {fid}; only "
                                      f"{', '.join(ALLOWED_HDF5_FILTERS.values())} are accepted "
                                      "(write it with compression='gzip' or none)")
        itemsize = ds.id.get_type().get_size()
        if ds.dtype.kind == "O" or h5py.check_vlen_dtype(ds.dtype) is not None:
            # variable-length items live in the global heap, bounded by the file size
            itemsize = max(itemsize, 16)
        shape = ds.shape or ()
        nbytes = math.prod(shape) * itemsize
        self.total_bytes += nbytes
        if self.total_bytes > self.max_bytes:
            raise UnsafeFileError(f"HDF5 dataset {path!r} has shape {shape} x {itemsize} bytes: the datasets "
                                  f"decompress to more than {self.max_bytes} bytes; send a shorter recording")
        if layout != h5py.h5d.CHUNKED:
            return  # contiguous/compact: stored raw, bounded by the file size and the shape check above
        chunk_shape = dcpl.get_chunk()
        chunk_bytes = math.prod(chunk_shape) * itemsize
        if chunk_bytes > self.max_bytes:
            raise UnsafeFileError(f"HDF5 dataset {path!r} has chunks of shape {chunk_shape} ({chunk_bytes} bytes "
                                  f"decompressed, more than {self.max_bytes}); rewrite it with smaller chunks")
        # the chunk grid bounds the chunks that can be allocated: decided from the metadata alone
        grid = math.prod(-(-int(n) // max(int(c), 1)) for n, c in zip(shape, chunk_shape)) if shape else 1
        if self.total_chunks + grid > self.max_chunks:
            raise UnsafeFileError(f"HDF5 dataset {path!r} of shape {shape} is stored in chunks of {chunk_shape}: up to "
                                  f"{grid} chunks, more than the {self.max_chunks} accepted in one file; rewrite it "
                                  "with larger chunks (e.g. h5py chunks=True) or without chunking")
        n_chunks = ds.id.get_num_chunks()
        if n_chunks > grid:
            raise UnsafeFileError(f"HDF5 dataset {path!r} claims {n_chunks} chunks in a grid of {grid}; the file is "
                                  "corrupt")
        self.total_chunks += n_chunks
        for i in range(n_chunks):
            stored = ds.id.get_chunk_info(i).size
            if stored <= 0 or chunk_bytes / stored > self.max_ratio:
                raise UnsafeFileError(
                    f"HDF5 dataset {path!r}: a chunk of {stored} stored bytes decompresses to {chunk_bytes} "
                    f"bytes (ratio {chunk_bytes / max(stored, 1):.0f}, more than {self.max_ratio:g}); such "
                    "compression bombs are refused — store the waveforms uncompressed or with normal gzip")


# --------------------------------------------------------------------------- NPY
def load_npy_bounded(data: bytes, *, max_bytes: int) -> np.ndarray:
    """Array from NPY bytes, with the declared size checked before anything is allocated.

    Parameters
    ----------
    data : bytes
        The whole NPY file (``numpy.save``), format version 1.0 or 2.0.
    max_bytes : int
        Bound on the array's size in bytes (shape x itemsize).

    Returns
    -------
    numpy.ndarray
        A writable copy of the array (never unpickled: object dtypes are refused).

    Raises
    ------
    UnsafeFileError
        Not NPY, an object/structured dtype, a size over ``max_bytes``, or a body
        whose length does not match the declared shape (truncated or padded).
    """
    if not data:
        raise UnsafeFileError("empty body: send an NPY file (numpy.save) with an (n_channels, n_points) array")
    if not bytes(data[:6]) == _NPY_MAGIC:
        raise UnsafeFileError("not an NPY file (it must start with the \\x93NUMPY magic); write it with numpy.save")
    fp = io.BytesIO(data)
    try:
        version = np.lib.format.read_magic(fp)
        if version == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(fp)
        elif version == (2, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(fp)
        else:
            raise UnsafeFileError(f"NPY format version {version} is not accepted; "
                                  "save a plain numeric array with numpy.save (version 1.0 or 2.0)")
    except UnsafeFileError:
        raise
    except (ValueError, OSError, EOFError, SyntaxError, TypeError, tokenize.TokenError) as exc:
        # numpy parses old-style headers with tokenize/ast, which raise their own errors on garbage
        raise UnsafeFileError(f"cannot read the NPY header (truncated or corrupt?): {exc}") from None
    if dtype.hasobject or dtype.fields is not None or dtype.kind not in "biufc":
        raise UnsafeFileError(f"NPY dtype {dtype} is not accepted; save a float32 or float64 array "
                              "(Python objects/pickles and record arrays are refused)")
    if any(int(n) < 0 for n in shape):
        raise UnsafeFileError(f"NPY header declares an invalid shape {shape}")
    count = math.prod(int(n) for n in shape)
    nbytes = count * dtype.itemsize
    if nbytes > max_bytes:
        raise UnsafeFileError(f"NPY array of shape {tuple(shape)} and dtype {dtype} is {nbytes} bytes, "
                              f"more than the {max_bytes} accepted; send a shorter recording")
    offset = fp.tell()
    body = len(data) - offset
    if body != nbytes:
        what = "truncated" if body < nbytes else "followed by extra bytes"
        raise UnsafeFileError(f"NPY body is {what}: the header declares shape {tuple(shape)} of {dtype} "
                              f"({nbytes} bytes) but {body} bytes follow; resend the complete file")
    flat = np.frombuffer(data, dtype=dtype, count=count, offset=offset)
    return np.array(flat.reshape(shape, order="F" if fortran else "C"), copy=True)


# --------------------------------------------------------------------------- JSON
_JSON_STRING = re.compile(rb'"(?:[^"\\]|\\.)*"', re.S)
_NOT_BRACKETS = bytes(c for c in range(256) if c not in b"[]{}")


def _depth_exceeds(raw: bytes, limit: int) -> bool:
    """Whether the brackets of JSON text nest deeper than ``limit`` (strings left out), at C and NumPy speed."""
    if raw.count(b"[") + raw.count(b"{") <= limit:
        return False
    brackets = np.frombuffer(_JSON_STRING.sub(b"", raw).translate(None, _NOT_BRACKETS), dtype=np.uint8)
    steps = np.where((brackets == ord("[")) | (brackets == ord("{")), 1, -1)
    return bool(brackets.size) and int(np.cumsum(steps).max()) > limit


def _refuse_constant(name: str) -> Any:
    raise UnsafeFileError(f"JSON contains {name}; numbers must be finite — send null or leave the value out "
                          "(NaN/Infinity are not valid JSON)")


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        shown = text if len(text) <= 40 else text[:40] + "..."
        raise UnsafeFileError(f"JSON number {shown} overflows to infinity; numbers must be finite "
                              "(at most ~1.8e308 in magnitude)")
    return value


def _bounded_int(text: str) -> int:
    if len(text.lstrip("-")) > 308:
        raise UnsafeFileError(f"JSON integer with {len(text)} digits is refused; numbers must be finite as floats "
                              "(at most ~1.8e308 in magnitude)")
    return int(text)


#: number spellings that may overflow a float (a 3-digit exponent, or 300+ digits in a row): only a body that
#: holds one is decoded number by number in Python; every other body at the C decoder's speed
_MAY_OVERFLOW = re.compile(rb"[eE][+]?0*[1-9][0-9]{2,}")
#: every digit to b"0", ``e``/``E`` to b"e", ``+`` kept, every other byte to b" ": the spellings that may overflow
#: are then found by substring searches
_NUMBER_MARKS = bytes(48 if 48 <= i <= 57 else 101 if i in (69, 101) else 43 if i == 43 else 32 for i in range(256))
_LONG_DIGIT_RUN = b"0" * 300


def _may_overflow(raw: bytes) -> bool:
    """Whether JSON text holds a number spelling that may overflow a float: a 3-digit exponent, or 300 digits
    in a row. On the text with its digits and exponent letters marked (one ``bytes.translate``), both are
    substrings (``e000``, ``e+000``: a positive exponent of three digits or more); only text that has such an
    exponent is searched with the exact regular expression (which, over a whole recording, took longer than
    decoding it)."""
    marks = raw.translate(_NUMBER_MARKS)
    return _LONG_DIGIT_RUN in marks or ((b"e000" in marks or b"e+000" in marks)
                                        and _MAY_OVERFLOW.search(raw) is not None)
#: JSON nesting deeper than this is refused before decoding (a recording needs 4 levels)
MAX_JSON_DEPTH = 64


#: an innermost JSON array (no bracket inside): where a channel's samples are
_INNER_ARRAY = re.compile(rb"\[[^\[\]]*\]")


def count_json_values(data: bytes, max_values: int, max_array: int | None = None) -> None:
    """Refuse JSON text that may hold more than ``max_values`` values, before anything is decoded.

    Every value after the first of an array or object is preceded by a comma, so the commas
    bound the count from above (commas inside strings only make the bound more cautious). The
    count runs at memory speed: a body is refused in milliseconds instead of being decoded into
    Python or pydantic objects that can take gigabytes.

    With ``max_array``, every innermost array (a channel's samples, a pulse train) is also held to
    ``max_array`` values, at the regular-expression engine's speed.

    Raises
    ------
    UnsafeFileError
        More than ``max_values`` commas, or an array of more than ``max_array`` values.
    """
    n = bytes(data[:4]).count(b"\x00")
    if n:                                            # UTF-16/32: count the commas of the decoded text
        try:
            data = data.decode(json.detect_encoding(data)).encode()
        except (UnicodeDecodeError, LookupError):
            return                                   # json.loads reports it
    if data.count(b",") > max_values:
        raise UnsafeFileError(f"JSON holds more than {max_values} values; send a shorter recording (fewer samples "
                              "per channel), split a batch, or send an NPY array")
    if max_array is not None and len(data) > 4 * max_array:      # shorter text cannot hold a longer array
        for start, end in _inner_arrays(data):
            if end - start > 2 * max_array and data.count(b",", start, end) >= max_array:
                raise UnsafeFileError(f"a JSON array holds more than {max_array} values; at most {max_array} "
                                      "samples per channel are accepted: send a shorter recording")


#: text with at most this many brackets has its innermost arrays found by ``bytes.find`` (else the regex)
_FEW_BRACKETS = 1024


def _inner_arrays(data: bytes) -> list[tuple[int, int]]:
    """(start, end) of every innermost array of JSON text: the matches of :data:`_INNER_ARRAY`, a ``[`` whose next
    bracket is a ``]``. A recording holds a handful of brackets around a megabyte of numbers, which the regular
    expression walks byte by byte (3.4 ms for the benchmark's 1.3 MB); ``bytes.find`` jumps from bracket to
    bracket. Text with many brackets takes the regular expression (the same matches)."""
    opening, closing = _positions(data, b"["), _positions(data, b"]")
    if opening is None or closing is None:
        return [(m.start(), m.end()) for m in _INNER_ARRAY.finditer(data)]
    marks = sorted(opening + closing)
    return [(i, j + 1) for i, j in zip(marks, marks[1:]) if data[i] == 0x5B and data[j] == 0x5D]


def _positions(data: bytes, byte: bytes) -> list[int] | None:
    """Every index of ``byte`` in ``data``; None when there are more than ``_FEW_BRACKETS``."""
    out: list[int] = []
    i = data.find(byte)
    while i >= 0:
        if len(out) == _FEW_BRACKETS:
            return None
        out.append(i)
        i = data.find(byte, i + 1)
    return out


def loads_json_finite(data: bytes | str, *, max_values: int | None = None) -> Any:
    """``json.loads`` that refuses non-finite numbers, and optionally bodies with too many values.

    Parameters
    ----------
    data : bytes or str
        JSON text (bytes in UTF-8/16/32, as ``json.loads`` detects).
    max_values : int, optional
        Refuse text that may hold more values than this before decoding it
        (:func:`count_json_values`).

    Returns
    -------
    Any
        The decoded value; every float in it is finite.

    Raises
    ------
    UnsafeFileError
        ``NaN``, ``Infinity``, ``-Infinity``, a float that overflows (``1e999``),
        an integer beyond float range, nesting too deep, or more than ``max_values`` values.
    json.JSONDecodeError
        Text that is not JSON (a ``ValueError`` whose message gives the position).
    """
    raw = data.encode() if isinstance(data, str) else bytes(data)
    if max_values is not None:
        count_json_values(raw, max_values)
    if _depth_exceeds(raw, MAX_JSON_DEPTH):
        raise UnsafeFileError(f"JSON is nested more than {MAX_JSON_DEPTH} levels deep; send a flat object")
    exact = b"\x00" in raw[:4] or _may_overflow(raw)
    try:
        if not exact:                                # no spelling that can overflow: the C decoder's floats are finite
            return json.loads(raw, parse_constant=_refuse_constant)
        return json.loads(data, parse_constant=_refuse_constant, parse_float=_finite_float,
                          parse_int=_bounded_int)
    except RecursionError:
        raise UnsafeFileError("JSON is nested too deeply; send a flat object") from None
    except UnicodeDecodeError as exc:
        raise UnsafeFileError(f"JSON body is not UTF-8 text: {exc}") from None


def check_json_finite(data: bytes) -> None:
    """What :func:`loads_json_finite` refuses, refused alike, without decoding text that cannot hold it.

    For a caller that decodes the text itself (pydantic's ``model_validate_json``): UTF-8 text (of valid
    encoding) without ``NaN`` or ``Infinity``, without a number spelling that may overflow and nested no deeper
    than ``MAX_JSON_DEPTH`` cannot be refused by it, so it is not decoded here (a recording's 1.3 MB decoded
    twice cost ~30 ms); any other goes through :func:`loads_json_finite`. Malformed JSON passes (the caller's
    decoder reports it with its position).

    Raises
    ------
    UnsafeFileError
        As :func:`loads_json_finite`.
    """
    raw = bytes(data)
    try:
        raw.decode("utf-8")
    except UnicodeDecodeError:
        plain = False
    else:
        plain = b"\x00" not in raw[:4]
    if plain and b"NaN" not in raw and b"Infinity" not in raw and not _may_overflow(raw) \
            and not _depth_exceeds(raw, MAX_JSON_DEPTH):
        return
    try:
        loads_json_finite(raw)
    except ValueError as exc:
        if isinstance(exc, UnsafeFileError):
            raise
