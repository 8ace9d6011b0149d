"""The recordings whose features ``tests/test_features_pinned.py`` pins, and the script that records them.

The features of these recordings were written to ``features_pinned.npz`` before the extractor was made faster
(issue 43 item 7): a speed-up must leave every value the same float to 1e-9 relative. The recordings: the shipped
examples (the file formats' readers included), the service benchmark's simulated plant (8 × 16,384 at 4096 Hz,
stored as float32 in the npz, as the benchmark sends it), and analytic waveforms (seeded noise) that take the other
ways through the extractor: an estimated speed, a keyphasor, a whirl line, a speed stated 0.3 % off, 3000 r/min.

Regenerate (only when a change of a feature's value is intended and explained):
``.venv/bin/python -m tests.reference.features_pinned``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

PINNED = Path(__file__).with_name("features_pinned.npz")
EXAMPLES = ("aligned.csv", "whirl.csv", "whirl.h5", "whirl.uff")
_LAYOUT = [(b, a) for b in (1, 2, 3, 4) for a in (45.0, 135.0)]


def _analytic(speed_rpm: float, fs: float, n: int, seed: int, whirl_x: float | None = None,
              amp_scale: float = 1.0) -> np.ndarray:
    """(8, n) µm: 1X–3X per bearing with bearing-dependent phases, a whirl line at ``whirl_x`` × 1X, seeded noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    th = 2 * np.pi * speed_rpm / 60.0 * t
    rows = []
    for b, a in _LAYOUT:
        ang = np.deg2rad(a)
        x = amp_scale * (30 / b * np.cos(th - 0.3 * b) + 8 * b * np.cos(2 * th - 0.7 * b) + 2 * np.cos(3 * th + b))
        y = amp_scale * (25 / b * np.sin(th - 0.3 * b) + 6 * b * np.sin(2 * th - 0.5 * b) + 1.5 * np.sin(3 * th - b))
        if whirl_x is not None:
            x = x + 12 * np.cos(whirl_x * th + b)
            y = y + 12 * np.sin(whirl_x * th + b)
        rows.append(x * np.cos(ang) + y * np.sin(ang) + 0.5 * rng.standard_normal(n) + 20.0 * b)
    return np.array(rows)


def recordings(bench_um: np.ndarray) -> dict[str, object]:
    """Name → ``features.Recording`` of every pinned case (``bench_um``: the benchmark's (8, 16384) float32)."""
    from rotordiag.features import ProbeChannel, Recording
    from rotordiag.features.examples import example_path
    from rotordiag.features.reader import read_recording

    def rec(data: np.ndarray, fs: float, **kw: object) -> Recording:
        return Recording(sample_rate_hz=fs, channels=[ProbeChannel(bearing=b, angle_deg=a, units="um", data=row)
                                                      for (b, a), row in zip(_LAYOUT, data)], **kw)

    out: dict[str, object] = {name: read_recording(example_path(name)).recording for name in EXAMPLES}
    bench = bench_um.astype(np.float64)
    out["bench_given"] = rec(bench, 4096.0, speed_rpm=1800.0)
    out["bench_estimated"] = rec(bench, 4096.0)
    out["bench_clearance"] = rec(bench, 4096.0, speed_rpm=1800.0, clearance_um=300.0)
    out["analytic_given_off"] = rec(_analytic(3009.0, 5120.0, 20_480, seed=1), 5120.0, speed_rpm=3000.0)
    out["analytic_estimated"] = rec(_analytic(3000.0, 5120.0, 20_480, seed=2), 5120.0)
    out["analytic_whirl"] = rec(_analytic(1800.0, 4096.0, 16_384, seed=3, whirl_x=0.45), 4096.0, speed_rpm=1800.0)
    kp = np.arange(0.0, 4.0, 60.0 / 1790.0) + 0.004
    out["analytic_keyphasor"] = rec(_analytic(1790.0, 4096.0, 16_384, seed=4) , 4096.0, keyphasor_times_s=kp)
    out["analytic_small"] = rec(_analytic(1800.0, 2048.0, 4096, seed=5, amp_scale=1e-3), 2048.0, speed_rpm=1800.0)
    return out


def summary(fr: object) -> dict[str, np.ndarray]:
    """What is pinned of one ``FeatureResult``: the vector, the speed, the revolutions, and the x/y order
    coefficients of each bearing."""
    out = {"values": np.asarray(fr.values, dtype=float),
           "speed_rpm": np.array([fr.speed_rpm]), "n_revs": np.array([fr.n_revs]),
           "warnings": np.array([w.code for w in fr.warnings] or [""]),
           "sanity": np.array([s.code for s in fr.sanity] or [""])}
    for b, d in fr.bearings.items():
        out[f"b{b}_coeffs"] = np.concatenate([d.x_coeffs_um, d.y_coeffs_um])
    return out


def main() -> None:
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    from benchmarks.bench_service import recording as bench_recording
    from rotordiag.features import extract_features

    bench_um = bench_recording()[0].astype(np.float32)
    arrays: dict[str, np.ndarray] = {"input_bench_um": bench_um}
    for name, r in recordings(bench_um).items():
        for key, v in summary(extract_features(r)).items():
            arrays[f"{name}/{key}"] = v
    np.savez_compressed(PINNED, **arrays)
    print(f"wrote {PINNED} ({PINNED.stat().st_size / 1e3:.0f} kB, {len(arrays)} arrays)")


if __name__ == "__main__":
    main()
