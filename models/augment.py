"""Measurement realities added when a training table is built (issue 15, item 5).

A dataset sample's probe waveforms already carry what the simulator's measurement model
draws per sample (runout, noise, speed fluctuation: ``simulator.dataset.measurement``). Two
realities of a plant's instrumentation are cheaper to add to the stored waveforms than to
simulate again, because they act on the measured signal as a whole:

- **probe gain mismatch**: each channel scaled by ``1 + u``, ``u`` uniform in
  ``[−gain_mismatch, +gain_mismatch]`` (a probe/driver sensitivity off its nominal
  7.87 V/mm; scaling the whole reading is exactly what it does);
- **missing bearings**: only a subset of the bearings instrumented (its channels dropped
  before extraction, so every feature of the other bearings is missing, as in the field);
- **speed unknown**: features extracted without the nominal speed, from the speed the
  extractor estimates (what a user without a keyphasor or a speed value gets);
- **less runout**: the sample's recorded shaft runout (1X and 2X, rebuilt exactly from the
  stored measurement draws: ``simulator.dataset.read.recorded_runout_um``) scaled by a factor
  ``U(0, 1)``, i.e. partly or wholly subtracted. The spec draws runout uniform in 0–6 µm (1X) and
  0–2 µm (2X) per bearing, so a well-kept shaft with almost none was rare in training; its
  recordings sat at the edge of the OOD reference and were flagged;
- **coupling journals apart**: bearing 3's static reading moved by U(0, ``journals_apart_c``)
  clearances in a uniform direction. The simulator ties the two coupling-end journals together
  (MODEL.md: r3 = r4 on an aligned train), so in its data a static offset between bearings 2 and 3 is
  always a shaft-line offset; on a real train each journal sits by its own load, and a gap referenced to
  another zero reads the same (docs/robustness.md, transfer check). ``journals_apart_models`` limits it to the
  samples of some simulations (``lumped``: the tied model; a finite-element train's journals already sit apart).

Each sample gets ``copies`` extra rows (the original row is kept unchanged); copies keep
the sample's plant id, so held-out evaluation never splits a plant. Draws come from
``numpy.random.default_rng([seed, sample_index, copy])``: a table is reproducible and a
sample's copies do not depend on which other samples are in the file.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

__all__ = ["Augmentation", "Variant"]

_KEYS = {"copies", "gain_mismatch", "bearing_sets", "speed_unknown", "runout_scaled", "journals_apart",
         "journals_apart_c", "journals_apart_models", "seed"}
#: how a sample was simulated (``simulator.dataset.spec.PlantSpec.model``; ``models.families.SIMULATIONS``)
_SIMULATIONS = ("lumped", "train")


@dataclass(frozen=True)
class Variant:
    """One augmented copy of a sample.

    Attributes
    ----------
    gains : ndarray of shape (n_channels,)
        Factor applied to each channel's waveform.
    keep : ndarray of bool, shape (n_channels,)
        Channels kept (the others' bearing is "not instrumented").
    speed_known : bool
        Whether the extractor is given the nominal speed.
    runout_scale : float
        Factor on the recorded runout (1 = as recorded, 0 = removed).
    journal3_shift_c : (float, float)
        Static shift (x, y) of bearing 3's reading, in clearances.
    """

    gains: np.ndarray
    keep: np.ndarray
    speed_known: bool
    runout_scale: float = 1.0
    journal3_shift_c: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class Augmentation:
    """The ``[augment]`` table of ``train.toml``.

    Parameters
    ----------
    copies : int
        Augmented rows per sample (0 = none).
    gain_mismatch : float
        Relative half-width of the per-channel gain error (0.1 = ±10 %).
    bearing_sets : sequence of (bearings, weight)
        Instrumented-bearing subsets a copy draws from (weights need not sum to 1); empty =
        every bearing of the dataset.
    speed_unknown : float
        Share of copies extracted without the nominal speed.
    runout_scaled : float
        Share of copies whose recorded runout is scaled by a factor drawn uniform in [0, 1].
    journals_apart : float
        Share of copies whose bearing-3 static reading is moved by U(0, ``journals_apart_c``) clearances in a
        uniform direction (needs the sample's clearance).
    journals_apart_c : float
        Largest such shift, in clearances.
    journals_apart_models : tuple of str
        The simulations whose samples get that shift (empty: every sample); :meth:`for_simulation` gives the
        augmentation of one dataset file.
    seed : int
    """

    copies: int = 0
    gain_mismatch: float = 0.0
    bearing_sets: tuple[tuple[tuple[int, ...], float], ...] = ()
    speed_unknown: float = 0.0
    runout_scaled: float = 0.0
    journals_apart: float = 0.0
    journals_apart_c: float = 0.3
    journals_apart_models: tuple[str, ...] = ()
    seed: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.copies, int) or not 0 <= self.copies <= 16:
            raise ValueError(f"[augment] copies: an integer in 0..16, got {self.copies!r}")
        if not 0.0 <= self.gain_mismatch < 0.5:
            raise ValueError(f"[augment] gain_mismatch: a relative half-width in [0, 0.5), got {self.gain_mismatch!r}")
        if not 0.0 <= self.speed_unknown <= 1.0:
            raise ValueError(f"[augment] speed_unknown: a share in [0, 1], got {self.speed_unknown!r}")
        if not 0.0 <= self.runout_scaled <= 1.0:
            raise ValueError(f"[augment] runout_scaled: a share in [0, 1], got {self.runout_scaled!r}")
        if not 0.0 <= self.journals_apart <= 1.0:
            raise ValueError(f"[augment] journals_apart: a share in [0, 1], got {self.journals_apart!r}")
        if not 0.0 <= self.journals_apart_c <= 1.0:
            raise ValueError(f"[augment] journals_apart_c: clearances in [0, 1], got {self.journals_apart_c!r}")
        if any(m not in _SIMULATIONS for m in self.journals_apart_models):
            raise ValueError(f"[augment] journals_apart_models: simulations among {list(_SIMULATIONS)}, "
                             f"got {list(self.journals_apart_models)}")
        for bearings, w in self.bearing_sets:
            if not bearings or any(b not in (1, 2, 3, 4) for b in bearings) or len(set(bearings)) != len(bearings):
                raise ValueError(f"[augment] bearing_sets: each set is distinct bearings 1–4, got {list(bearings)}")
            if not w >= 0:
                raise ValueError(f"[augment] bearing_sets: weights must be ≥ 0, got {w!r}")
        if self.bearing_sets and sum(w for _, w in self.bearing_sets) <= 0:
            raise ValueError("[augment] bearing_sets: the weights are all zero")

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> Augmentation:
        """From the TOML table: ``bearing_sets = [{bearings = [2, 3], weight = 1}, ...]``."""
        d = dict(d or {})
        unknown = set(d) - _KEYS
        if unknown:
            raise ValueError(f"[augment]: unknown key(s) {sorted(unknown)}; allowed: {sorted(_KEYS)}")
        sets = []
        for item in d.get("bearing_sets", ()):
            if not isinstance(item, Mapping) or "bearings" not in item:
                raise ValueError(f"[augment] bearing_sets: each item is {{bearings = [...], weight = w}}, got {item!r}")
            sets.append((tuple(int(b) for b in item["bearings"]), float(item.get("weight", 1.0))))
        seed = d.get("seed", 0)
        copies = d.get("copies", 0)
        if not isinstance(seed, int) or seed < 0:
            raise ValueError(f"[augment] seed: a non-negative integer, got {seed!r}")
        return cls(copies=copies, gain_mismatch=float(d.get("gain_mismatch", 0.0)), bearing_sets=tuple(sets),
                   speed_unknown=float(d.get("speed_unknown", 0.0)),
                   runout_scaled=float(d.get("runout_scaled", 0.0)),
                   journals_apart=float(d.get("journals_apart", 0.0)),
                   journals_apart_c=float(d.get("journals_apart_c", 0.3)),
                   journals_apart_models=tuple(str(m) for m in d.get("journals_apart_models", ())), seed=seed)

    def to_dict(self) -> dict:
        return {"copies": self.copies, "gain_mismatch": self.gain_mismatch,
                "bearing_sets": [{"bearings": list(b), "weight": w} for b, w in self.bearing_sets],
                "speed_unknown": self.speed_unknown, "runout_scaled": self.runout_scaled, "seed": self.seed,
                **({"journals_apart": self.journals_apart, "journals_apart_c": self.journals_apart_c}
                   if self.journals_apart > 0 else {}),
                **({"journals_apart_models": list(self.journals_apart_models)}
                   if self.journals_apart > 0 and self.journals_apart_models else {})}

    def for_simulation(self, model: str | None) -> Augmentation:
        """The augmentation of a dataset file whose samples were simulated by ``model`` (``lumped``, ``train``;
        None: not recorded): without the journals' shift when ``journals_apart_models`` leaves that model out, so
        the file's rows and cache key are those of an augmentation without it."""
        if self.journals_apart == 0 or not self.journals_apart_models or model in self.journals_apart_models:
            return self
        return replace(self, journals_apart=0.0, journals_apart_models=())

    @property
    def key(self) -> str:
        """A string that changes whenever the augmented rows would (for the feature cache)."""
        return repr(sorted(self.to_dict().items()))

    def variants(self, sample_index: int, channel_bearings: Sequence[int]) -> list[Variant]:
        """The ``copies`` variants of one sample whose channels sit at ``channel_bearings``."""
        bearings = np.asarray(channel_bearings, dtype=int)
        out = []
        present = set(bearings.tolist())
        sets = [(tuple(b), w) for b, w in self.bearing_sets if set(b) <= present] or [(tuple(sorted(present)), 1.0)]
        weights = np.array([w for _, w in sets], dtype=float)
        weights = weights / weights.sum()
        for c in range(self.copies):
            rng = np.random.default_rng([self.seed, int(sample_index), c])
            gains = 1.0 + rng.uniform(-self.gain_mismatch, self.gain_mismatch, size=bearings.size)
            chosen = sets[int(rng.choice(len(sets), p=weights))][0]
            keep = np.isin(bearings, chosen)
            speed_known = bool(rng.uniform() >= self.speed_unknown)
            scale = 1.0
            if self.runout_scaled > 0 and rng.uniform() < self.runout_scaled:   # drawn after the others:
                scale = float(rng.uniform())                                  # their draws stay as before
            shift = (0.0, 0.0)
            if self.journals_apart > 0 and rng.uniform() < self.journals_apart:     # after those: the same
                r, a = rng.uniform(0.0, self.journals_apart_c), rng.uniform(0.0, 2.0 * np.pi)
                shift = (float(r * np.cos(a)), float(r * np.sin(a)))
            out.append(Variant(gains=gains, keep=keep, speed_known=speed_known, runout_scale=scale,
                               journal3_shift_c=shift))
        return out
