"""Summaries of dataset files (``rotordiag dataset info``)."""
from __future__ import annotations

import json
import os
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from .store import TRANSIENT_GROUP, StoreError, open_dataset, sample_kind

__all__ = ["summarize"]


def _counts(codes: np.ndarray, names: dict[int, str]) -> dict[str, int]:
    out: dict[str, int] = {}
    for code in sorted(set(codes.tolist())):
        out[names.get(int(code), f"code {code}")] = int(np.count_nonzero(codes == code))
    return out


def summarize(path: str | os.PathLike) -> dict[str, Any]:
    """Counts per class / status / mechanism / motion kind and parameter ranges of the finished samples.

    Returns
    -------
    dict
        JSON-serialisable summary.
    """
    path = Path(path)
    try:
        return _summarize(path)
    except KeyError as exc:  # h5py names the missing object in the message
        raise StoreError(f"{path} lacks part of the rotordiag dataset layout ({exc}); it was written by an "
                         f"older or different program: regenerate it with this version") from None


def _summarize(path: Path) -> dict[str, Any]:
    with open_dataset(path) as f:
        done = f["done"][...].astype(bool)
        n_done = int(done.sum())
        sev_names = json.loads(f["labels/severity"].attrs["names_json"])
        status_codes = {v: k for k, v in json.loads(f["labels/status"].attrs["codes_json"]).items()}
        mech_codes = {v: k for k, v in json.loads(f["parameters/simulated_mechanism"].attrs["codes_json"]).items()}
        summary: dict[str, Any] = {
            "path": str(path),
            "format_version": int(f.attrs["format_version"]),
            "merged": bool(f.attrs.get("merged", False)),
            "spec_hash": str(f.attrs["spec_hash"]),
            "code_version": str(f.attrs["code_version"]),
            "created_utc": str(f.attrs["created_utc"]),
            "resume_log": [json.loads(x) for x in f["resume_log"][...] if x],
            "n_samples": int(done.size),
            "n_done": n_done,
            "n_channels": int(f.attrs["n_channels"]),
            "n_points": int(f.attrs["n_points"]),
            "sample_rate_hz": float(f.attrs["sample_rate_hz"]),
            "channels": [{"bearing": int(b), "angle_deg": float(a)} for b, a in f["channels"][...].tolist()],
            "file_bytes": path.stat().st_size,
            "bytes_per_done_sample": round(path.stat().st_size / n_done) if n_done else None,
        }
        sev = f["labels/severity"][...][done]
        summary["severity_counts"] = {name: int(np.count_nonzero(sev == k)) for k, name in enumerate(sev_names)}
        summary["status_counts"] = _counts(f["labels/status"][...][done], status_codes)
        summary["mechanism_counts"] = _counts(f["parameters/simulated_mechanism"][...][done], mech_codes)
        kinds = f["labels/motion_kind"][...][done]
        periods = f["labels/motion_period"][...][done]
        labels = [k.decode() + (f"-{p}" if k == b"period-n" else "") if k else "unlabelled"
                  for k, p in zip(kinds, periods)]
        labels = [lab.replace("period-n-", "period-") for lab in labels]
        summary["motion_counts"] = {k: labels.count(k) for k in sorted(set(labels))}
        summary["n_plants"] = int(len(set(f["parameters/plant_id"][...][done].tolist())))
        if "parameters/plant_source" in f:
            summary["plant_source_counts"] = dict(sorted(Counter(
                p.decode() for p in f["parameters/plant_source"][...][done]).items()))
        ranges = {}
        for name in ("speed_rpm", "misalignment", "unbalance", "exciter_unbalance", "offset_angle_rad"):
            v = f[f"parameters/{name}"][...][done]
            if v.size:
                ranges[name] = [float(v.min()), float(v.max())]
        for name in f["parameters/plant"]:
            ds = f[f"parameters/plant/{name}"]
            if ds.dtype.kind != "f":
                continue
            v = ds[...][done]
            if not v.size:
                continue
            cols = v.reshape(v.shape[0], -1)
            for j in range(cols.shape[1]):
                lo, hi = float(cols[:, j].min()), float(cols[:, j].max())
                if hi != lo:
                    where = "" if v.ndim == 1 else str([int(k) for k in np.unravel_index(j, v.shape[1:])])
                    ranges[f"plant.{name}{where}"] = [lo, hi]
        summary["parameter_ranges"] = ranges
        summary["sample_kind"] = sample_kind(f)
        if summary["sample_kind"] == "transient":
            g = f[TRANSIENT_GROUP]
            kp = g["keyphasor_times_s"][...][done]
            profiles = {(tuple(t), tuple(n)) for t, n in zip(g["profile_times_s"][...][done].tolist(),
                                                           g["profile_speeds_rpm"][...][done].tolist())}
            summary["transient"] = {
                "what": "each sample is a run-up or coast-down through a speed profile, with a keyphasor: "
                        "read it with DatasetReader.transient_sample (steady readers refuse this file)",
                "profiles": [{"times_s": list(t), "speeds_rpm": list(n)} for t, n in sorted(profiles)],
                "record_s": (int(f.attrs["n_points"]) - 1) / float(f.attrs["sample_rate_hz"]),
                "keyphasor_marks": int(g["keyphasor_times_s"].shape[1]),
                "stopped_early": int(np.count_nonzero(np.any(~np.isfinite(kp), axis=1))) if kp.size else 0,
            }
            ranges.pop("speed_rpm", None)  # parameters/speed_rpm of a run-up is its profile's top speed
        if summary["merged"]:
            summary["sources"] = json.loads(f.attrs["sources_json"])
    return summary
