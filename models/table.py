"""A labelled feature table: the input of training and evaluation."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ._patterns import name_mask


@dataclass
class FeatureTable:
    """Feature rows with their labels and grouping.

    Attributes
    ----------
    X : ndarray of shape (n_samples, n_features), float64 (NaN = missing feature)
    feature_names : tuple of str
    misalignment : ndarray (n_samples,) — true Δ = δ/c
    plant_id : ndarray (n_samples,) — plant-parameter set; evaluation splits on it
    mechanism : ndarray (n_samples,) of str — "pin" | "rigid" | "aligned"
    speed_rpm : ndarray (n_samples,)
    sample_index : ndarray (n_samples,) — row in the source dataset
    meta : dict — provenance (dataset path, hash, spec, plant family, skipped samples)
    offset_angle_rad : ndarray (n_samples,) or None — direction of the exciter's offset from the generator's line
        (from +x, horizontal, toward +y, vertical up; the dataset's ``parameters/offset_angle_rad``); None when the
        dataset does not record it
    angular_mrad : ndarray (n_samples,) or None — angular offset α at the coupling (mrad, along
        ``offset_angle_rad``; ``parameters/angular_misalignment_mrad``); None when the dataset does not record it
    """

    X: np.ndarray
    feature_names: tuple[str, ...]
    misalignment: np.ndarray
    plant_id: np.ndarray
    mechanism: np.ndarray
    speed_rpm: np.ndarray
    sample_index: np.ndarray | None = None
    meta: dict = field(default_factory=dict)
    offset_angle_rad: np.ndarray | None = None
    angular_mrad: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.X = np.asarray(self.X, dtype=float)
        n = self.X.shape[0]
        self.feature_names = tuple(str(s) for s in self.feature_names)
        if self.X.ndim != 2 or self.X.shape[1] != len(self.feature_names):
            raise ValueError(
                f"X: expected (n_samples, {len(self.feature_names)}) to match feature_names, got {self.X.shape}"
            )
        self.misalignment = np.asarray(self.misalignment, dtype=float)
        self.plant_id = np.asarray(self.plant_id)
        self.mechanism = np.asarray(self.mechanism).astype(str).astype(object)
        self.speed_rpm = np.asarray(self.speed_rpm, dtype=float)
        if self.sample_index is None:
            self.sample_index = np.arange(n)
        for name in ("offset_angle_rad", "angular_mrad"):
            if getattr(self, name) is not None:
                setattr(self, name, np.asarray(getattr(self, name), dtype=float))
        for name in ("misalignment", "plant_id", "mechanism", "speed_rpm", "sample_index", "offset_angle_rad",
                     "angular_mrad"):
            if getattr(self, name) is not None and getattr(self, name).shape != (n,):
                raise ValueError(f"{name}: expected shape ({n},), got {getattr(self, name).shape}")

    def __len__(self) -> int:
        return self.X.shape[0]

    def _sample_index(self) -> np.ndarray:
        assert self.sample_index is not None  # set by __post_init__
        return self.sample_index

    def subset(self, rows) -> FeatureTable:
        """Rows selected by a boolean mask or index array."""
        return FeatureTable(
            self.X[rows], self.feature_names, self.misalignment[rows], self.plant_id[rows],
            self.mechanism[rows], self.speed_rpm[rows], self._sample_index()[rows], dict(self.meta),
            None if self.offset_angle_rad is None else self.offset_angle_rad[rows],
            None if self.angular_mrad is None else self.angular_mrad[rows],
        )

    @classmethod
    def concat(cls, tables: Sequence[FeatureTable]) -> FeatureTable:
        """Rows of several tables (same feature names) in one; ``meta["sources"]`` lists
        each table's meta and ``meta["source"]`` the table index of each row."""
        tables = list(tables)
        if not tables:
            raise ValueError("concat: no tables")
        if len(tables) == 1:
            return tables[0]
        names = tables[0].feature_names
        for k, t in enumerate(tables[1:], 1):
            if t.feature_names != names:
                raise ValueError(f"DATA: file {k + 1} has a different feature schema from file 1")
        out = cls(
            np.vstack([t.X for t in tables]), names,
            np.concatenate([t.misalignment for t in tables]),
            np.concatenate([t.plant_id.astype(object) for t in tables]),
            np.concatenate([t.mechanism for t in tables]),
            np.concatenate([t.speed_rpm for t in tables]),
            np.concatenate([t.sample_index for t in tables]),
            offset_angle_rad=_concat_labels([t.offset_angle_rad for t in tables]),
            angular_mrad=_concat_labels([t.angular_mrad for t in tables]),
        )
        out.meta = {
            "sources": [dict(t.meta) for t in tables],
            "source": np.concatenate([np.full(len(t), k) for k, t in enumerate(tables)]),
        }
        return out

    def feature_mask(self, patterns: Sequence[str]) -> np.ndarray:
        """Boolean mask of the columns whose names match any glob pattern."""
        return name_mask(self.feature_names, patterns)

    def without_features(self, patterns: Sequence[str]) -> FeatureTable:
        """Drop the columns whose names match any glob pattern."""
        if not patterns:
            return self
        keep = np.flatnonzero(~name_mask(self.feature_names, patterns)).tolist()
        if not keep:
            raise ValueError(f"features.exclude: {list(patterns)} removes every feature")
        return FeatureTable(
            self.X[:, keep], tuple(self.feature_names[i] for i in keep), self.misalignment,
            self.plant_id, self.mechanism, self.speed_rpm, self.sample_index, dict(self.meta),
            self.offset_angle_rad, self.angular_mrad,
        )

    @property
    def has_direction_labels(self) -> bool:
        """Whether every row carries the direction of its offset (``offset_angle_rad``)."""
        return self.offset_angle_rad is not None and bool(np.isfinite(self.offset_angle_rad).all())


def _concat_labels(parts: Sequence[np.ndarray | None]) -> np.ndarray | None:
    """The tables' label arrays in one, or None when any table lacks them (a label only some rows have is none)."""
    if any(p is None for p in parts):
        return None
    return np.concatenate([np.asarray(p, dtype=float) for p in parts])
