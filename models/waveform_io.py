"""Read probe waveforms from CSV, NPY or HDF5 into a :class:`features.Recording`.

The layout of the channels (bearing and mounting angle of each probe), the sample rate,
the units, and optionally the speed, keyphasor times and bearing clearance come from a
small JSON sidecar (``rec.csv`` → ``rec.json`` by default), from the file itself where it
says them, and from explicit overrides (CLI flags), in increasing priority::

    {
      "sample_rate_hz": 2560,
      "units": "um",                                  # um | mm | m | mil
      "channels": [{"bearing": 1, "angle_deg": 45}, {"bearing": 1, "angle_deg": 135}, ...],
      "speed_rpm": 1800,                              # optional
      "keyphasor_times_s": [0.0, 0.0333, ...],        # optional
      "clearance_um": 350                             # optional: one value or {"1": .., "2": ..}
    }

Formats:

- **CSV**: one column per probe, one row per sample. A header is optional; header names
  of the form ``b<bearing>@<angle>`` (``b2@45``) give the channel layout themselves. A
  column named ``time_s`` is ignored (its spacing must match the sample rate if both are
  given, else it gives the sample rate).
- **NPY**: a 2-D float array (channels × points); plain arrays only (never pickles).
- **HDF5**: a rotordiag dataset file (``--sample`` picks the row; layout, rate, speed and
  clearance are read from the file) or any file with a 2-D ``waveforms`` dataset
  (channels × points) and optional ``sample_rate_hz``/``units`` attributes and a
  ``channels`` table (``bearing``, ``angle_deg``).
"""
from __future__ import annotations

import csv
import json
import re
from pathlib import Path
from typing import Any, Mapping

import numpy as np

MAX_POINTS = 10_000_000
_HEADER_RE = re.compile(r"^\s*b([1-4])\s*@\s*(-?\d+(?:\.\d*)?)\s*$", re.IGNORECASE)


def _layout_from(items) -> list[tuple[int, float]]:
    out = []
    for k, c in enumerate(items):
        try:
            out.append((int(c["bearing"]), float(c["angle_deg"])))
        except (KeyError, TypeError, ValueError):
            raise ValueError(
                f"channels[{k}]: each channel needs 'bearing' (1–4) and 'angle_deg', got {c!r}"
            ) from None
    return out


def _read_csv(path: Path) -> tuple[np.ndarray, dict]:
    info: dict = {}
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    rows = [r for r in rows if r and any(cell.strip() for cell in r)]
    if not rows:
        raise ValueError(f"{path}: the CSV file is empty")
    header = None
    try:
        [float(v) for v in rows[0]]
    except ValueError:
        header, rows = [h.strip() for h in rows[0]], rows[1:]
    if len(rows) > MAX_POINTS:
        raise ValueError(f"{path}: more than {MAX_POINTS} rows")
    try:
        data = np.array([[float(v) for v in r] for r in rows], dtype=float)
    except ValueError as exc:
        raise ValueError(f"{path}: non-numeric value in the CSV data ({exc})") from None
    if data.ndim != 2 or data.shape[0] == 0:
        raise ValueError(f"{path}: rows of the CSV file have different lengths")
    if header is not None:
        if len(header) != data.shape[1]:
            raise ValueError(f"{path}: header has {len(header)} names for {data.shape[1]} columns")
        if "time_s" in header:
            j = header.index("time_s")
            t = data[:, j]
            if t.size > 1:
                dt = np.diff(t)
                if np.all(dt > 0) and np.ptp(dt) <= 1e-6 * dt.mean() + 1e-12:
                    info["sample_rate_hz_from_time"] = 1.0 / dt.mean()
            data = np.delete(data, j, axis=1)
            header = header[:j] + header[j + 1:]
        matches = [_HEADER_RE.match(h) for h in header]
        if all(matches):
            info["channels"] = [{"bearing": int(m.group(1)), "angle_deg": float(m.group(2))} for m in matches]
    return data.T, info


def _read_h5(path: Path, sample: int | None) -> tuple[np.ndarray, dict]:
    import h5py

    info: dict = {}
    try:
        f = h5py.File(path, "r")
    except OSError:
        try:
            f = h5py.File(path, "r", swmr=True)
        except OSError as exc:
            raise ValueError(f"{path}: not a readable HDF5 file ({exc})") from None
    with f:
        if "waveforms" not in f:
            raise ValueError(f"{path}: no 'waveforms' dataset in the HDF5 file")
        wf = f["waveforms"]
        if "channels" in f:
            ch = f["channels"][...]
            info["channels"] = [{"bearing": int(b), "angle_deg": float(a)} for b, a in zip(ch["bearing"], ch["angle_deg"])]
        for key in ("sample_rate_hz", "units", "waveform_units", "speed_rpm", "clearance_um"):
            if key in f.attrs:
                v = f.attrs[key]
                info["units" if key == "waveform_units" else key] = v.decode() if isinstance(v, bytes) else (
                    v.item() if hasattr(v, "item") else v)
        if wf.ndim == 3:
            n = wf.shape[0]
            if sample is None:
                raise ValueError(f"{path}: a dataset file with {n} samples; choose one with --sample INDEX")
            if not 0 <= sample < n:
                raise ValueError(f"--sample: {sample} is outside 0..{n - 1}")
            if "done" in f and not f["done"][sample]:
                raise ValueError(f"--sample: sample {sample} of {path} is not finished")
            data = wf[sample].astype(float)
            if "parameters/speed_rpm" in f:
                info["speed_rpm"] = float(f["parameters/speed_rpm"][sample])
            if "parameters/plant/clearance_m" in f:
                info["clearance_um"] = float(f["parameters/plant/clearance_m"][sample]) * 1e6
            if "labels/misalignment" in f:
                info["truth"] = {"misalignment": float(f["labels/misalignment"][sample])}
        elif wf.ndim == 2:
            data = wf[...].astype(float)
        else:
            raise ValueError(f"{path}: 'waveforms' must be 2-D (channels × points) or 3-D (samples × channels × points)")
    return data, info


def read_recording(
    path: str | Path,
    *,
    sidecar: str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
    sample: int | None = None,
):
    """Build a :class:`features.Recording` from a waveform file.

    Parameters
    ----------
    path : CSV, NPY or HDF5 file
    sidecar : JSON file, optional
        Default: the file with the same stem and ``.json`` suffix, when it exists.
    overrides : mapping, optional
        ``sample_rate_hz``, ``units``, ``channels`` (list of {bearing, angle_deg}),
        ``speed_rpm``, ``clearance_um``, ``keyphasor_times_s``; ``None`` values are ignored.
    sample : int, optional
        Row of a dataset HDF5 file.

    Returns
    -------
    (Recording, info) — ``info`` holds what was read (and ``truth`` for dataset rows).

    Raises
    ------
    ValueError
        Naming what is missing or wrong (unknown format, missing sample rate or channel
        layout, channel count mismatch, ...).
    """
    from features import ProbeChannel, Recording

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"FILE: {path} does not exist")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        data, info = _read_csv(path)
    elif suffix == ".npy":
        try:
            data = np.load(path, allow_pickle=False)
        except ValueError as exc:
            raise ValueError(f"{path}: not a plain numeric .npy array ({exc})") from None
        if data.ndim != 2 or not np.issubdtype(data.dtype, np.number):
            raise ValueError(f"{path}: .npy must hold a 2-D numeric array (channels × points), got {data.shape} {data.dtype}")
        data, info = data.astype(float), {}
    elif suffix in (".h5", ".hdf5", ".hdf"):
        data, info = _read_h5(path, sample)
    else:
        raise ValueError(f"FILE: unknown format {suffix!r}; use .csv, .npy or .h5/.hdf5")
    side: dict = {}
    side_path = Path(sidecar) if sidecar is not None else path.with_suffix(".json")
    if sidecar is not None and not side_path.is_file():
        raise ValueError(f"--sidecar: {side_path} does not exist")
    if side_path.is_file() and side_path != path:
        try:
            side = json.loads(side_path.read_text())
        except json.JSONDecodeError as exc:
            raise ValueError(f"sidecar {side_path}: not valid JSON ({exc})") from None
        if not isinstance(side, dict):
            raise ValueError(f"sidecar {side_path}: must be a JSON object")
        allowed = {"sample_rate_hz", "units", "channels", "speed_rpm", "clearance_um", "keyphasor_times_s"}
        unknown = set(side) - allowed
        if unknown:
            raise ValueError(f"sidecar {side_path}: unknown key(s) {sorted(unknown)}; allowed: {sorted(allowed)}")
    merged: dict = {**info, **side, **{k: v for k, v in (overrides or {}).items() if v is not None}}
    fs = merged.get("sample_rate_hz", info.get("sample_rate_hz_from_time"))
    if fs is None:
        raise ValueError("sample rate unknown: give --sample-rate-hz or 'sample_rate_hz' in the sidecar JSON")
    if "channels" not in merged:
        raise ValueError(
            "channel layout unknown: give --channels (e.g. '1@45,1@135,2@45,2@135'), 'channels' in the "
            "sidecar JSON, or CSV headers like 'b1@45'"
        )
    layout = _layout_from(merged["channels"])
    if data.shape[0] != len(layout):
        if data.shape[1] == len(layout):
            data = data.T          # points × channels
        else:
            raise ValueError(
                f"the file has {data.shape[0]} channels (rows) × {data.shape[1]} points but the layout names "
                f"{len(layout)} channels"
            )
    if data.shape[1] > MAX_POINTS:
        raise ValueError(f"{path}: more than {MAX_POINTS} points per channel")
    units = str(merged.get("units", "um"))
    clearance = merged.get("clearance_um")
    if isinstance(clearance, dict):
        clearance = {int(k): float(v) for k, v in clearance.items()}
    kp = merged.get("keyphasor_times_s")
    rec = Recording(
        sample_rate_hz=float(fs),
        channels=[ProbeChannel(bearing=b, angle_deg=a, units=units, data=data[i]) for i, (b, a) in enumerate(layout)],
        speed_rpm=None if merged.get("speed_rpm") is None else float(merged["speed_rpm"]),
        keyphasor_times_s=None if kp is None else np.asarray(kp, dtype=float),
        clearance_um=clearance,
    )
    return rec, info


def parse_channels(text: str) -> list[dict]:
    """Parse ``'1@45,1@135,2@45'`` into ``[{"bearing": 1, "angle_deg": 45.0}, ...]``."""
    out = []
    for part in text.split(","):
        m = re.match(r"^\s*b?([1-4])\s*@\s*(-?\d+(?:\.\d*)?)\s*$", part)
        if not m:
            raise ValueError(f"--channels: {part!r} is not BEARING@ANGLE (e.g. '2@45')")
        out.append({"bearing": int(m.group(1)), "angle_deg": float(m.group(2))})
    return out
