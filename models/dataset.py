"""Dataset HDF5 (docs/dataset-format.md) → labelled feature table, with a feature cache.

Each finished sample with status ``ok`` becomes one row: its eight probe waveforms go
through :func:`features.extract_features` — the same function the service uses — with
the sample's nominal speed and its plant's bearing clearance. Samples that are not
finished or whose status is not ``ok`` are skipped and counted by reason.

Extraction is the slow part, so the feature matrix is cached next to the dataset as
``<file>.features-<key>.npz`` (plain arrays, loaded with ``allow_pickle=False``). The key
hashes the dataset content (waveforms, labels, plant ids, spec), the feature schema and
the source code of the ``features`` package, so a changed dataset or feature extractor
never serves stale features.
"""
from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from rotordiag.core.units import factor_to_um

from .augment import Augmentation, Variant
from .table import FeatureTable

_CACHE_VERSION = 1


def _open(path: Path):
    import h5py

    try:
        return h5py.File(path, "r")
    except OSError:
        # A run killed mid-write leaves HDF5's "being written" flag: SWMR reading works.
        return h5py.File(path, "r", swmr=True)


def _codes(ds) -> dict[int, str]:
    raw = ds.attrs.get("codes_json")
    if raw is None:
        return {}
    d = json.loads(raw)
    return {int(v): str(k) for k, v in d.items()}


def _str_array(a) -> np.ndarray:
    return np.array([v.decode() if isinstance(v, bytes) else str(v) for v in a], dtype=object)


def features_code_hash() -> str:
    """SHA-256 of the ``features`` package source, every module below it, and the schema's names (what the cached
    values depend on: ``rotordiag.core.version.source_hash``)."""
    from rotordiag import features
    from rotordiag.core.version import source_hash

    text = source_hash(Path(features.__file__).parent) + "|" + "|".join(features.FEATURE_NAMES)
    return hashlib.sha256(text.encode()).hexdigest()


def dataset_hash(path: str | Path) -> str:
    """SHA-256 of a dataset's content: spec, finished flags, labels, plant ids, waveforms.

    Time attributes and wall times are left out, so two runs of one spec hash alike.
    """
    path = Path(path)
    h = hashlib.sha256()
    with _open(path) as f:
        for key in ("spec_hash", "sources_json", "sample_rate_hz", "n_points"):
            if key in f.attrs:
                h.update(f"{key}={f.attrs[key]!r}".encode())
        for name in ("done", "labels/status", "labels/misalignment", "parameters/plant_id",
                     "parameters/speed_rpm", "parameters/simulated_mechanism", "channels"):
            if name in f:
                h.update(name.encode())
                h.update(np.ascontiguousarray(f[name][...]).tobytes())
        wf = f["waveforms"]
        for i in range(wf.shape[0]):
            h.update(np.ascontiguousarray(wf[i]).tobytes())
    return h.hexdigest()


def _extract_rows(f, rows, progress: Callable | None, augment: Augmentation | None = None,
                  ) -> tuple[np.ndarray, list[str], list[tuple[int, str]]]:
    """Features of the samples ``rows``; with ``augment``, of their augmented copies instead
    (``len(rows) * augment.copies`` rows, copy-major within each sample)."""
    from rotordiag.features import FEATURE_NAMES, ProbeChannel, Recording, extract_features
    from rotordiag.simulator.dataset.read import recorded_runout_um

    fs = float(f.attrs["sample_rate_hz"])
    units = str(f.attrs.get("waveform_units", "um"))
    ch = f["channels"][...]
    bearings = [int(b) for b in ch["bearing"]]
    angles = [float(a) for a in ch["angle_deg"]]
    speed = f["parameters/speed_rpm"][...]
    clearance_m = f["parameters/plant/clearance_m"][...] if "parameters/plant/clearance_m" in f else None
    copies = augment.copies if augment is not None else 1
    X = np.full((len(rows) * copies, len(FEATURE_NAMES)), np.nan)
    failed: list[tuple[int, str]] = []
    wf = f["waveforms"]
    for k, i in enumerate(rows):
        data = wf[i]
        if augment is None:
            variants = [Variant(np.ones(len(bearings)), np.ones(len(bearings), bool), True)]
        else:
            variants = augment.variants(int(i), bearings)
        for c, v in enumerate(variants):
            try:
                w = data
                if v.runout_scale != 1.0 and "measurement" in f:
                    w = data - (1.0 - v.runout_scale) * recorded_runout_um(f, int(i))
                if v.journal3_shift_c != (0.0, 0.0) and clearance_m is not None:
                    per_unit = float(clearance_m[i]) * 1e6 / factor_to_um(units)      # clearance in the file's units
                    sx, sy = (per_unit * s for s in v.journal3_shift_c)
                    w = w + np.array([[sx * np.cos(np.deg2rad(a)) + sy * np.sin(np.deg2rad(a)) if b == 3 else 0.0]
                                      for b, a in zip(bearings, angles)])
                rec = Recording(
                    sample_rate_hz=fs,
                    channels=[ProbeChannel(bearing=b, angle_deg=a, units=units, data=w[j] * v.gains[j])
                              for j, (b, a) in enumerate(zip(bearings, angles)) if v.keep[j]],
                    speed_rpm=float(speed[i]) if v.speed_known else None,
                    clearance_um=None if clearance_m is None else float(clearance_m[i]) * 1e6,
                )
                X[k * copies + c] = extract_features(rec).values
            except ValueError as exc:
                failed.append((int(i), str(exc)))
        if progress is not None:
            progress(k + 1, len(rows))
    return X, list(FEATURE_NAMES), failed


def load_feature_table(
    path: str | Path,
    *,
    cache: bool = True,
    progress: Callable[[int, int], None] | None = None,
    augment: Augmentation | None = None,
) -> FeatureTable:
    """Feature table of a dataset file (finished, ``ok`` samples only).

    Parameters
    ----------
    path : path to a rotordiag dataset HDF5 file
    cache : bool, default=True
        Read/write the feature cache next to the file.
    progress : callable(done, total), optional
        Called after each extracted sample.
    augment : Augmentation, optional
        Add ``augment.copies`` rows per sample with measurement realities
        (:mod:`rotordiag.models.augment`), after the original rows; cached separately.

    Returns
    -------
    FeatureTable
        ``meta`` holds ``dataset_path``, ``dataset_hash``, ``dataset_spec`` (the validated
        spec JSON), ``plant_family`` and ``skipped`` (counts by reason).

    Raises
    ------
    ValueError
        Not a rotordiag dataset, or no usable sample.
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"dataset: file {path} does not exist")
    try:
        f = _open(path)
    except OSError as exc:
        raise ValueError(f"dataset: {path} is not a readable HDF5 file ({exc})") from None
    with f:
        if f.attrs.get("format") != "rotordiag-dataset":
            raise ValueError(f"dataset: {path} is not a rotordiag dataset (attribute format != 'rotordiag-dataset')")
        from rotordiag.simulator.dataset.store import StoreError, require_kind

        try:
            require_kind(f, "steady", "the feature table (steady features per sample)")
        except StoreError as exc:
            raise ValueError(f"dataset: {exc}") from None
        done = f["done"][...].astype(bool)
        status_codes = _codes(f["labels/status"])
        status = np.array([status_codes.get(int(s), f"code {int(s)}") for s in f["labels/status"][...]], dtype=object)
        mech_codes = _codes(f["parameters/simulated_mechanism"])
        mechanism = np.array([mech_codes.get(int(m), str(int(m))) for m in f["parameters/simulated_mechanism"][...]],
                             dtype=object)
        ok = done & (status == "ok")
        skipped = {"not finished": int((~done).sum())}
        for s in sorted(set(status[done].tolist()) - {"ok"}):
            skipped[f"status {s}"] = int(np.sum(done & (status == s)))
        rows = np.flatnonzero(ok)
        if rows.size == 0:
            raise ValueError(f"dataset: {path} has no finished sample with status ok ({skipped})")
        spec = f.attrs.get("spec_json")
        base_plant = f.attrs.get("base_plant_json")
        family: dict[str, Any] = {
            "base_plant": json.loads(base_plant) if base_plant else None,
            "perturb": (json.loads(spec).get("plant", {}) if spec else {}),
        }
        meta = {
            "dataset_path": str(path),
            "dataset_spec": json.loads(spec) if spec else None,
            "plant_family": family,
        }
        if f.attrs.get("merged"):
            meta["dataset_sources"] = json.loads(f.attrs["sources_json"])
        sources = f.attrs.get("plant_sources_json")
        if sources and len(json.loads(sources)) > 1:  # a machine family: every base plant with its weight
            family["sources"] = json.loads(sources)
        t0 = time.perf_counter()
        data_hash = dataset_hash(path)
        meta["dataset_hash"] = data_hash
        key = hashlib.sha256(f"{_CACHE_VERSION}|{data_hash}|{features_code_hash()}".encode()).hexdigest()[:16]
        cache_path = path.with_name(f"{path.name}.features-{key}.npz")
        X: np.ndarray | None = None
        names: list[str] | None = None
        failed: list[tuple[int, str]] = []
        if cache and cache_path.is_file():
            try:
                with np.load(cache_path, allow_pickle=False) as z:
                    if np.array_equal(z["rows"], rows):
                        X, names = z["X"], [str(n) for n in z["names"]]
                        failed = [(int(i), str(m)) for i, m in zip(z["failed_rows"], z["failed_msgs"])]
            except (OSError, KeyError, ValueError):
                X = None
        meta["feature_cache"] = {"path": str(cache_path), "hit": X is not None}
        if X is None:
            X, names, failed = _extract_rows(f, rows, progress)
            if cache:
                tmp = cache_path.with_name(cache_path.name + ".tmp.npz")
                np.savez(tmp, X=X, names=np.array(names), rows=rows,
                         failed_rows=np.array([i for i, _ in failed], dtype=np.int64),
                         failed_msgs=np.array([m for _, m in failed], dtype=str))
                tmp.replace(cache_path)
        meta["feature_time_s"] = round(time.perf_counter() - t0, 2)
        if failed:
            skipped["feature extraction failed"] = len(failed)
            meta["feature_failures"] = failed[:20]
        meta["skipped"] = skipped
        good = np.ones(rows.size, bool)
        if failed:
            bad = {i for i, _ in failed}
            good = np.array([i not in bad for i in rows])
        r = rows[good]
        assert X is not None and names is not None
        X = X[good]
        if augment is not None and augment.copies > 0:
            augment = augment.for_simulation(_simulation(f))
            X_aug = _augmented_rows(f, r, augment, key, path, cache)
            ok_aug = ~np.all(np.isnan(X_aug), axis=1)
            failed_aug = int((~ok_aug).sum())
            off = _speed_estimate_off(X_aug, names, f["parameters/speed_rpm"][...][np.repeat(r, augment.copies)])
            ok_aug &= ~off
            meta["augment"] = {**augment.to_dict(), "rows": int(ok_aug.sum()), "failed": failed_aug,
                               "speed_estimate_off": int(off.sum())}
            r = np.concatenate([r, np.repeat(r, augment.copies)[ok_aug]])
            X = np.vstack([X, X_aug[ok_aug]])
        return FeatureTable(
            X=X,
            feature_names=tuple(names),
            misalignment=f["labels/misalignment"][...][r],
            plant_id=_str_array(f["parameters/plant_id"][...][r]),
            mechanism=mechanism[r],
            speed_rpm=f["parameters/speed_rpm"][...][r],
            sample_index=r,
            meta=meta,
            offset_angle_rad=f["parameters/offset_angle_rad"][...][r] if "parameters/offset_angle_rad" in f else None,
            # α only in files whose spec varies it (simulator.dataset.store.ANGULAR_DATASETS)
            angular_mrad=(f["parameters/angular_misalignment_mrad"][...][r]
                          if "parameters/angular_misalignment_mrad" in f else None),
        )


#: A speed-unknown copy whose estimated speed misses the simulated one by more than this is left
#: out of training: its order features (1X, 2X … read at the wrong speed) describe no machine, and
#: such a recording gets the "speed estimate ambiguous" reason (or lies outside the training speed
#: range) rather than a verdict learned from them. Keeping them had put 242–10 540 r/min into the
#: training range of ``speed_rpm`` (1200–3600 simulated), so an estimate at 1/5 of the true speed
#: (period-5 motion) passed the feature envelope.
SPEED_COPY_MAX_ERROR = 0.02


def _speed_estimate_off(X: np.ndarray, names: list[str], true_speed_rpm: np.ndarray) -> np.ndarray:
    """Rows whose ``speed_rpm`` feature (estimated when the copy withheld the speed; the given
    value otherwise) misses ``true_speed_rpm`` by more than ``SPEED_COPY_MAX_ERROR``."""
    est = X[:, list(names).index("speed_rpm")]
    with np.errstate(invalid="ignore", divide="ignore"):
        err = np.abs(est / np.asarray(true_speed_rpm, dtype=float) - 1.0)
    return np.isfinite(est) & (err > SPEED_COPY_MAX_ERROR)


def _simulation(f) -> str | None:
    """How the file's samples were simulated (its spec's ``plant.model``, ``lumped`` when the spec leaves it out as
    specs written before trains do); None for a file without a spec."""
    spec = f.attrs.get("spec_json")
    return str((json.loads(spec).get("plant") or {}).get("model", "lumped")) if spec else None


def _augmented_rows(f, rows: np.ndarray, augment: Augmentation, key: str, path: Path, cache: bool) -> np.ndarray:
    """Features of the augmented copies of ``rows`` (cached next to the dataset, keyed by the augmentation)."""
    akey = hashlib.sha256(f"{key}|{augment.key}".encode()).hexdigest()[:16]
    cache_path = path.with_name(f"{path.name}.augmented-{akey}.npz")
    if cache and cache_path.is_file():
        try:
            with np.load(cache_path, allow_pickle=False) as z:
                if np.array_equal(z["rows"], rows):
                    return np.asarray(z["X"])
        except (OSError, KeyError, ValueError):
            pass
    X, _names, _failed = _extract_rows(f, rows, None, augment)
    if cache:
        tmp = cache_path.with_name(cache_path.name + ".tmp.npz")
        np.savez(tmp, X=X, rows=rows)
        tmp.replace(cache_path)
    return X


def load_feature_tables(paths, *, cache: bool = True, augment: Augmentation | None = None) -> FeatureTable:
    """:func:`load_feature_table` of each file, concatenated (one model from several files).

    The combined ``dataset_hash`` is the SHA-256 of the files' hashes in order; the other
    provenance fields become lists.
    """
    tables = [load_feature_table(p, cache=cache, augment=augment) for p in paths]
    if len(tables) == 1:
        return tables[0]
    out = FeatureTable.concat(tables)
    metas = out.meta["sources"]
    out.meta.update({
        "dataset_path": [m["dataset_path"] for m in metas],
        "dataset_hash": hashlib.sha256("|".join(m["dataset_hash"] for m in metas).encode()).hexdigest(),
        "dataset_hashes": [m["dataset_hash"] for m in metas],
        "dataset_spec": [m["dataset_spec"] for m in metas],
        "plant_family": [m["plant_family"] for m in metas],
        "skipped": {m["dataset_path"]: m["skipped"] for m in metas},
        "feature_time_s": round(sum(m["feature_time_s"] for m in metas), 2),
        "feature_cache": {"hit": all(m["feature_cache"]["hit"] for m in metas)},
    })
    del out.meta["sources"]
    del out.meta["source"]
    return out
