"""Synthetic feature tables with known structure for the models tests.

Each "plant" has its own aligned 2X/1X level (the two-pole generator's gravity-sag
2X, 0.2–0.8), so a 2X/1X threshold false-alarms on aligned plants, while a
coupling phase feature tracks Δ monotonically on every plant. The generator is
deterministic given its seed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

FEATURE_NAMES = (
    "b2_x_2x_1x_ratio",
    "b3_x_2x_1x_ratio",
    "coupling_1x_phase_diff_deg",
    "b1_x_1x_amp_um",
    "b1_x_1x_amp_per_clearance",
    "noise_a",
    "noise_b",
)


@dataclass
class SyntheticTable:
    X: np.ndarray
    misalignment: np.ndarray
    plant_id: np.ndarray
    mechanism: np.ndarray
    speed_rpm: np.ndarray
    feature_names: tuple[str, ...] = FEATURE_NAMES


def make_table(n_plants: int = 60, per_plant: int = 12, seed: int = 0,
               nan_rate: float = 0.0) -> SyntheticTable:
    rng = np.random.default_rng(seed)
    rows, deltas, plants, mechs, speeds = [], [], [], [], []
    for p in range(n_plants):
        r0 = rng.uniform(0.2, 0.8)        # plant's own 2X/1X when aligned
        gain = rng.uniform(0.8, 1.2)
        mech = "rigid" if p % 2 == 0 else "pin"
        for _ in range(per_plant):
            delta = 0.0 if rng.random() < 0.25 else rng.uniform(0.0, 0.6)
            speed = rng.uniform(1200, 3000)
            ratio_shift = 1.2 * delta * gain
            phase = 170.0 * delta / (delta + 0.1) * gain + rng.normal(0, 3.0)
            amp = rng.uniform(20, 60) * (1 + delta)
            row = [
                r0 + ratio_shift + rng.normal(0, 0.03),
                r0 * 0.9 + ratio_shift + rng.normal(0, 0.03),
                phase,
                amp,
                amp / 350.0,
                rng.normal(),
                rng.normal(),
            ]
            rows.append(row)
            deltas.append(delta)
            plants.append(p)
            mechs.append(mech if delta > 0 else "aligned")
            speeds.append(speed)
    X = np.asarray(rows, dtype=float)
    if nan_rate > 0:
        X[rng.random(X.shape) < nan_rate] = np.nan
    return SyntheticTable(X, np.asarray(deltas), np.asarray(plants), np.asarray(mechs, dtype=object),
                          np.asarray(speeds))
