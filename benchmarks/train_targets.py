"""Issue 48's targets for held-out simulated trains, measured on the judged trains of ``models/trains/``.

    .venv/bin/python benchmarks/train_targets.py --data data/trains [--registry models/default_registry]

The recordings are ``benchmarks/train_verdict.py``'s (its docstring builds them), judged with the speed and the
clearance stated. Printed against each target: the confident share; of the confident answers, those in the true band
and within one band; false alarms (a healthy train given any misalignment class, any status); Δ ≥ 0.15 given
slight or worse; the 90 % interval's coverage of the true Δ; and the offset's direction on the confident answers with
Δ ≥ 0.15 and DC positions, "right" when within 45° of the true direction (the quadrant it names: high or low,
left or right). Counts are given with each share: n is small.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from train_verdict import judge, read_samples  # noqa: E402

#: a direction within this of the true one is right
DIRECTION_RIGHT_DEG = 45.0
#: Δ from which a misalignment is "moderate or worse" (issue 48, item 5)
MODERATE_DELTA = 0.15


def _share(k: int, n: int) -> str:
    return f"{100.0 * k / n:.1f} % ({k} of {n})" if n else "– (0 of 0)"


def target_rows(bundle, samples: list[dict], outs: list) -> list[tuple[str, str, str]]:
    """(target, measured, issue 48's bound) for the judged ``outs`` of ``samples``."""
    names = list(bundle.model.bands_.names)
    edges = np.asarray(bundle.model.bands_.edges, dtype=float)
    delta = np.array([o.delta for o in outs])
    true_band = np.searchsorted(edges, delta, side="right")
    shown = np.array([names.index(o.model_class) if o.model_class in names else -1 for o in outs])
    confident = np.array([o.status == "confident" for o in outs])
    off = np.abs(shown - true_band)
    lo, hi = np.array([o.interval[0] for o in outs]), np.array([o.interval[1] for o in outs])
    has = np.isfinite(lo) & np.isfinite(hi)
    covered = has & (delta >= lo) & (delta <= hi)
    healthy, moderate = delta == 0.0, delta >= MODERATE_DELTA
    n_dir = n_right = 0
    for s, o, c in zip(samples, outs, confident):
        if c and o.delta >= MODERATE_DELTA and o.dc_available and math.isfinite(o.direction_deg):
            n_dir += 1
            error = abs((o.direction_deg - math.degrees(s["offset_angle_rad"]) + 180.0) % 360.0 - 180.0)
            n_right += error <= DIRECTION_RIGHT_DEG
    return [
        ("confident answers", _share(int(confident.sum()), len(outs)), "≥ 70 %"),
        ("confident answers in the true band", _share(int((confident & (off == 0)).sum()), int(confident.sum())), "≥ 98 %"),
        ("confident answers within one band", _share(int((confident & (off <= 1)).sum()), int(confident.sum())), "100 %"),
        ("false alarms (healthy, any class but aligned)",
         _share(int((healthy & (shown != 0)).sum()), int(healthy.sum())), "≤ 3 %"),
        (f"Δ ≥ {MODERATE_DELTA} given slight or worse", _share(int((moderate & (shown >= 1)).sum()), int(moderate.sum())),
         "≥ 97 %"),
        ("90 % interval covers the true Δ", _share(int(covered.sum()), int(has.sum())), "85–95 %"),
        (f"direction within {DIRECTION_RIGHT_DEG:g}° (confident, Δ ≥ {MODERATE_DELTA}, DC)", _share(n_right, n_dir), "≥ 90 %"),
    ]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--data", type=Path, default=ROOT / "data" / "trains")
    ap.add_argument("--registry", type=Path, default=ROOT / "models" / "default_registry")
    args = ap.parse_args(argv)
    from rotordiag.models.predict import load_bundle

    bundle = load_bundle(args.registry)
    samples = read_samples(args.data)
    outs = judge(bundle, samples, "speed and clearance stated")
    print(f"model {bundle.version}, {len(samples)} judged trains, speed and clearance stated\n")
    print("| target | measured | issue 48 |\n|---|---|---|")
    for row in target_rows(bundle, samples, outs):
        print("| " + " | ".join(row) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
