"""Join dataset files of one family into one file (``rotordiag dataset merge``).

A *family* is a set of files with the same layout: the same datasets, shapes
and dtypes (so the same plant fields and number of bearings), the same channel
table, sample rate, points per channel, waveform compression and severity
bands. Specs may differ otherwise (ranges, mechanisms, seeds, plants). Only
finished samples (``done == 1``) are copied, compressed waveform chunks as they
are. A file given twice, or two files made from the same spec (which hold the
same samples), are refused. The result records its sources (``sources_json``
attribute and a per-sample ``source`` index) and is marked ``merged``; it
cannot be resumed by ``generate``.
"""
from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .store import FORMAT, FORMAT_VERSION, StoreError, _dataset_names, _fsync_dir, create_file, open_dataset

__all__ = ["merge"]

_SAME_ATTRS = ("n_channels", "n_points", "sample_rate_hz", "waveform_units", "severity_bands_json", "format_version")


def _signature(f: Any) -> dict[str, Any]:
    sig = {name: (f[name].shape[1:], f[name].dtype.str) for name in _dataset_names(f)}
    return {
        "datasets": sig,
        "channels": f["channels"][...].tolist(),
        "compression": f["waveforms"].compression,
        "attrs": {k: (f.attrs[k].item() if hasattr(f.attrs[k], "item") else f.attrs[k]) for k in _SAME_ATTRS},
    }


def merge(inputs: Sequence[str | os.PathLike], out: str | os.PathLike) -> dict[str, Any]:
    """Merge the finished samples of ``inputs`` into a new file ``out``.

    Returns
    -------
    dict
        ``{"n_samples": total, "sources": [...]}``.

    Raises
    ------
    StoreError
        Fewer than two inputs, an existing ``out``, files of different
        families, or duplicated specs; the message says which file and why.
    """
    import h5py

    from rotordiag.core.version import code_version

    paths = [Path(p) for p in inputs]
    out = Path(out)
    if len(paths) < 2:
        raise StoreError("merge needs at least two input files")
    if out.exists():
        raise StoreError(f"{str(out)!r} already exists; merge writes a new file")
    if any(p.resolve() == out.resolve() for p in paths):
        raise StoreError("the output file cannot be one of the inputs")
    sources: list[dict[str, Any]] = []
    ref_sig: dict[str, Any] | None = None
    seen_hashes: dict[str, str] = {}
    offsets: list[int] = []
    for p in paths:
        with open_dataset(p) as f:
            sig = _signature(f)
            if ref_sig is None:
                ref_sig, ref_path = sig, p
                L = {name: (tuple(shape), np.dtype(dt).str.lstrip("<>|=")) for name, (shape, dt) in sig["datasets"].items()
                     if name != "source"}
                channels = [tuple(c) for c in f["channels"][...].tolist()]
                dattrs = {name: {k: f[name].attrs[k] for k in f[name].attrs} for name in L}
                base_attrs = {k: f.attrs[k] for k in _SAME_ATTRS}
            else:
                a = {k: v for k, v in sig.items()}
                b = {k: v for k, v in ref_sig.items()}
                a["datasets"].pop("source", None)
                b["datasets"].pop("source", None)
                if a != b:
                    diff = [k for k in a if a[k] != b[k]]
                    raise StoreError(f"{str(p)!r} is not of the same family as {str(ref_path)!r} "
                                     f"(differs in: {', '.join(diff)}); only files with the same measurement "
                                     "layout, plant fields and severity bands can be merged")
            if f.attrs.get("merged", False):  # a merged input contributes its own sources
                own = json.loads(f.attrs["sources_json"])
            else:
                own = [{"file": p.name, "spec_hash": str(f.attrs["spec_hash"]),
                        "code_version": str(f.attrs["code_version"]),
                        "n_samples": int(np.count_nonzero(f["done"][...])),
                        "spec_toml": str(f.attrs.get("spec_toml", ""))}]
            for h in own:
                if h["spec_hash"] in seen_hashes:
                    raise StoreError(f"{str(p)!r} and {seen_hashes[h['spec_hash']]!r} come from the same spec "
                                     f"(hash {h['spec_hash'][:12]}…) and hold the same samples; merge each spec once")
                seen_hashes[h["spec_hash"]] = str(p)
            offsets.append(len(sources))
            sources.extend(own)
    total = sum(s["n_samples"] for s in sources)
    if total == 0:
        raise StoreError("the input files hold no finished samples")
    L["source"] = ((), "i2")
    attrs = dict(base_attrs)
    attrs.update({
        "format": FORMAT, "format_version": FORMAT_VERSION, "merged": True,
        "spec_toml": "", "spec_json": "",
        "spec_hash": hashlib.sha256("".join(sorted(s["spec_hash"] for s in sources)).encode()).hexdigest(),
        "sources_json": json.dumps(sources), "code_version": code_version(),
        "created_utc": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "n_samples": total, "design_method": "merged", "master_seed": -1,
        "base_plant_json": "",
    })
    dattrs["source"] = {"description": "index into the sources_json attribute"}
    tmp = out.with_name(out.name + ".merging")
    assert ref_sig is not None  # at least one input was read
    create_file(tmp, total, L, channels, attrs, dattrs, compression=ref_sig["compression"] or "gzip")
    with h5py.File(tmp, "r+", libver="latest") as dst:
        row = 0
        for k, p in enumerate(paths):
            with open_dataset(p) as src:
                idx = np.flatnonzero(src["done"][...])
                n = idx.size
                if n == 0:
                    continue
                sw, dw = src["waveforms"], dst["waveforms"]
                tail = (0,) * (sw.ndim - 1)
                for j, i in enumerate(idx):
                    mask, chunk = sw.id.read_direct_chunk((int(i), *tail))
                    dw.id.write_direct_chunk((row + j, *tail), chunk, mask)
                for name in L:
                    if name == "waveforms":
                        continue
                    if name == "source":
                        local = src["source"][...][idx] if "source" in src else np.zeros(n, dtype="i2")
                        dst["source"][row:row + n] = local + offsets[k]
                        continue
                    dst[name][row:row + n] = src[name][...][idx]
                row += n
        dst.flush()
    os.replace(tmp, out)
    _fsync_dir(out.parent)
    return {"n_samples": total, "sources": [{k: v for k, v in s.items() if k != "spec_toml"} for s in sources]}
