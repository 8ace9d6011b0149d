"""Reading dataset files without hard-coding their layout (for training, features, notebooks).

>>> from simulator.dataset import DatasetReader
>>> with DatasetReader("data.h5") as ds:                       # doctest: +SKIP
...     table = ds.labels()                                   # finished samples only
...     for i, w in ds.iter_waveforms():                      # (n_channels, n_points) µm, one at a time
...         ...

Works on complete files, on files being written and on files of a killed run
(see :func:`simulator.dataset.store.open_dataset`).
"""
from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from .measurement import MeasurementDraws, MeasurementSettings, runout_um, shaft_angle_rad
from .store import TRANSIENT_GROUP, open_dataset, require_kind, sample_kind

__all__ = ["DatasetReader", "TransientSample", "recorded_runout_um"]


@dataclass(frozen=True)
class TransientSample:
    """One run-up or coast-down sample of a transient dataset file (a ``[transient]`` spec).

    Attributes
    ----------
    index : int
        Row in the file.
    waveforms_um : ndarray, shape (n_channels, n_points), float32
        Probe displacements toward each probe (µm, DC kept); NaN past the end of a run that stopped early.
    sample_rate_hz : float
    channels : list of (int, float)
        (bearing, angle_deg) per channel.
    profile_times_s, profile_speeds_rpm : ndarray
        The run's speed profile (straight lines between the points).
    keyphasor_times_s : ndarray
        Once-per-revolution marks inside the record (s from its start; shaft angle 0 at each).
    status : str
        The simulator's: ``ok``, ``contact``, ``diverged`` or ``error``.
    clearance_m : float
        The sample plant's radial clearance.
    """

    index: int
    waveforms_um: np.ndarray
    sample_rate_hz: float
    channels: list[tuple[int, float]]
    profile_times_s: np.ndarray
    profile_speeds_rpm: np.ndarray
    keyphasor_times_s: np.ndarray
    status: str
    clearance_m: float

    @property
    def time_s(self) -> np.ndarray:
        """Sample times from the record's start (s)."""
        return np.arange(self.waveforms_um.shape[-1]) / self.sample_rate_hz

    @property
    def speed_rpm(self) -> np.ndarray:
        """The profile's speed at each sample (r/min)."""
        return np.interp(self.time_s, self.profile_times_s, self.profile_speeds_rpm)

    @property
    def n_valid_points(self) -> int:
        """Points recorded before the run ended (all of them unless it stopped early)."""
        finite = np.all(np.isfinite(self.waveforms_um), axis=0)
        return int(finite.size if finite.all() else np.argmin(finite))

    def keyphasor_signal(self, notch_fraction: float = 0.1) -> np.ndarray:
        """A keyphasor probe's signal at the samples (a −1 notch at each mark), as ``rotordiag runup`` writes it."""
        from rotordiag.simulator.transient import keyphasor_pulse_signal

        return keyphasor_pulse_signal(self.time_s, self.sample_rate_hz, self.keyphasor_times_s, notch_fraction)


def _decode(codes: np.ndarray, codes_json: str) -> np.ndarray:
    names = {v: k for k, v in json.loads(codes_json).items()}
    return np.array([names.get(int(c), "") for c in codes], dtype=object)


def _measurement_table(f: Any, i: int) -> dict[str, Any]:
    """The validated ``[measurement]`` table that row ``i`` was measured with: the file's spec, or for a
    merged file (no spec of its own) the spec of the row's source."""
    import tomllib

    from .spec import Measurement

    text = str(f.attrs.get("spec_json", ""))
    if text:
        return dict(json.loads(text)["measurement"])
    if f.attrs.get("merged", False) and "source" in f:
        src = json.loads(f.attrs["sources_json"])[int(f["source"][i])]
        table = tomllib.loads(str(src.get("spec_toml", ""))).get("measurement", {})
        return Measurement.model_validate(table).model_dump()
    raise ValueError("the dataset file records no spec: the runout it added cannot be rebuilt")


def recorded_runout_um(f: Any, index: int) -> np.ndarray:
    """The runout part of row ``index``'s stored waveforms, (n_channels, n_points) µm.

    Rebuilt from the sample's stored measurement draws (``measurement/*``) and the spec's
    speed fluctuation with :func:`simulator.dataset.measurement.runout_um`, exactly as the
    measurement model added it; ``waveforms - recorded_runout_um(...)`` is the same recording of
    a shaft without runout (the noise stays as drawn).

    Parameters
    ----------
    f : an open dataset file (h5py.File)
    index : int
        Row.
    """
    require_kind(f, "steady", "recorded_runout_um")
    i = int(index)
    m = _measurement_table(f, i)
    n_points = int(f["waveforms"].shape[-1])
    channels = [(int(b), float(a)) for b, a in f["channels"][...].tolist()]
    bearings = tuple(int(b) for b in m["bearings"])
    settings = MeasurementSettings(bearings=bearings, probe_angles_deg=tuple(float(a) for a in m["probe_angles_deg"]),
                                   sample_rate_hz=float(f.attrs["sample_rate_hz"]), n_points=n_points,
                                   speed_fluctuation=float(m["speed_fluctuation"]),
                                   speed_fluctuation_hz=float(m["speed_fluctuation_hz"]))
    g = f["measurement"]
    draws = MeasurementDraws(float(g["snr_db"][i]), float(g["start_angle_rad"][i]),
                             float(g["speed_fluctuation_phase_rad"][i]), g["runout_1x_um"][i], g["runout_1x_phase_rad"][i],
                             g["runout_2x_um"][i], g["runout_2x_phase_rad"][i])
    theta = shaft_angle_rad(settings.time_s, float(f["parameters/speed_rpm"][i]), settings, draws)
    return np.stack([runout_um(theta, a, draws, bearings.index(b)) for b, a in channels])


class DatasetReader:
    """Read-only view of a dataset file.

    Attributes
    ----------
    done : ndarray of bool, shape (n_samples,)
    indices : ndarray of int
        Rows of the finished samples.
    sample_rate_hz : float
    channels : list of (int, float)
        (bearing, angle_deg) per channel.
    attrs : dict
        File attributes (spec text, spec hash, code version, ...).
    kind : str
        ``"steady"`` (one speed per sample: :meth:`waveforms`, :meth:`iter_waveforms`) or ``"transient"``
        (run-ups / coast-downs: :meth:`transient_sample`); each refuses the other kind's file.
    """

    def __init__(self, path: str | os.PathLike):
        self.path = path
        self._cm: contextlib.AbstractContextManager[Any] | None = open_dataset(path)
        self.f = self._cm.__enter__()
        self.done = self.f["done"][...].astype(bool)
        self.indices = np.flatnonzero(self.done)
        self.sample_rate_hz = float(self.f.attrs["sample_rate_hz"])
        self.channels = [(int(b), float(a)) for b, a in self.f["channels"][...].tolist()]
        self.attrs = {k: (v.item() if hasattr(v, "item") else v) for k, v in self.f.attrs.items()}
        self.kind = sample_kind(self.f)

    def close(self) -> None:
        if self._cm is not None:
            self._cm.__exit__(None, None, None)
            self._cm = None

    def __enter__(self) -> DatasetReader:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __len__(self) -> int:
        return int(self.indices.size)

    def labels(self, only_done: bool = True) -> dict[str, np.ndarray]:
        """Per-sample labels and key parameters, decoded to plain values.

        Returns
        -------
        dict of ndarray
            ``index`` (row), ``misalignment``, ``severity`` (int), ``severity_name``,
            ``status``, ``mechanism`` (simulated: pin/rigid/aligned),
            ``design_mechanism`` (pin/rigid), ``motion`` (e.g. "period-1"),
            ``plant_id``, ``speed_rpm``, ``unbalance``, ``clearance_m``,
            ``sample_seed``, ``plant_source`` (the base plant's label, e.g.
            ``preset:gen200_2pole``; absent in older files); plus ``source`` for merged files.
        """
        f = self.f
        rows = self.indices if only_done else np.arange(self.done.size)
        sev = f["labels/severity"][...][rows]
        names = np.array(json.loads(f["labels/severity"].attrs["names_json"]), dtype=object)
        kinds = f["labels/motion_kind"][...][rows]
        periods = f["labels/motion_period"][...][rows]
        motion = np.array([(f"period-{p}" if k == b"period-n" else k.decode()) for k, p in zip(kinds, periods)],
                          dtype=object)
        out = {
            "index": rows,
            "misalignment": f["labels/misalignment"][...][rows],
            "severity": sev.astype(int),
            "severity_name": np.where(sev >= 0, names[np.clip(sev, 0, len(names) - 1)], ""),
            "status": _decode(f["labels/status"][...][rows], f["labels/status"].attrs["codes_json"]),
            "mechanism": _decode(f["parameters/simulated_mechanism"][...][rows],
                                 f["parameters/simulated_mechanism"].attrs["codes_json"]),
            "design_mechanism": _decode(f["parameters/mechanism"][...][rows],
                                        f["parameters/mechanism"].attrs["codes_json"]),
            "motion": motion,
            "plant_id": np.array([p.decode() for p in f["parameters/plant_id"][...][rows]], dtype=object),
            "speed_rpm": f["parameters/speed_rpm"][...][rows],
            "unbalance": f["parameters/unbalance"][...][rows],
            "clearance_m": f["parameters/plant/clearance_m"][...][rows],
            "sample_seed": f["parameters/sample_seed"][...][rows],
        }
        if "parameters/plant_source" in f:  # files written before machine families lack it
            out["plant_source"] = np.array([p.decode() for p in f["parameters/plant_source"][...][rows]], dtype=object)
        if "source" in f:
            out["source"] = f["source"][...][rows]
        return out

    def parameters(self, name: str, only_done: bool = True) -> np.ndarray:
        """Any per-sample dataset by its path, e.g. ``"parameters/plant/asymmetry"``."""
        rows = self.indices if only_done else np.arange(self.done.size)
        return self.f[name][...][rows]

    def waveforms(self, index: int) -> np.ndarray:
        """Waveforms of steady row ``index``: (n_channels, n_points) float32, µm (a transient file: refused)."""
        require_kind(self.f, "steady", "DatasetReader.waveforms")
        return self.f["waveforms"][int(index)]

    def runout_um(self, index: int) -> np.ndarray:
        """The runout part of row ``index``'s waveforms (:func:`recorded_runout_um`)."""
        return recorded_runout_um(self.f, index)

    def iter_waveforms(self, indices: np.ndarray | None = None) -> Iterator[tuple[int, np.ndarray]]:
        """Yield ``(row, waveforms)`` one steady sample at a time (memory stays flat); default: finished samples."""
        require_kind(self.f, "steady", "DatasetReader.iter_waveforms")
        for i in (self.indices if indices is None else indices):
            yield int(i), self.f["waveforms"][int(i)]

    def transient_sample(self, index: int) -> TransientSample:
        """Run-up / coast-down row ``index`` with its profile and keyphasor (a steady file: refused)."""
        require_kind(self.f, "transient", "DatasetReader.transient_sample")
        i = int(index)
        if not 0 <= i < self.done.size:
            raise IndexError(f"sample index {i} out of range [0, {self.done.size})")
        if not self.done[i]:
            raise ValueError(f"sample {i} is not finished (done = 0): nothing to read")
        g = self.f[TRANSIENT_GROUP]
        kp = g["keyphasor_times_s"][i]
        status = _decode(self.f["labels/status"][i:i + 1], self.f["labels/status"].attrs["codes_json"])[0]
        return TransientSample(i, self.f["waveforms"][i], self.sample_rate_hz, list(self.channels),
                               g["profile_times_s"][i], g["profile_speeds_rpm"][i], kp[np.isfinite(kp)],
                               str(status), float(self.f["parameters/plant/clearance_m"][i]))
