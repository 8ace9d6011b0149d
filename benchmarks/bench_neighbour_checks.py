"""The two checks that compare a recording with the training machines nearest it, measured on datasets' features.

    .venv/bin/python benchmarks/bench_neighbour_checks.py DATASET.h5 [DATASET.h5 ...] [--registry DIR] [--n 200]

For each dataset (its cached features, ``models.dataset.load_feature_table``; the first ``--n`` rows), with the
model of ``--registry`` (default: the shipped one):

- **A backward 1X at one bearing** (``models.checks.backward_whirl``): of the coupling bearings (2, 3) whose 1X
  whirls backward (whirl index below ``features.REVERSE_WHIRL_INDEX``), the share the check reads as the machine's
  (at least ``MIN_BACKWARD`` of the ``N_NEIGHBOURS`` nearest training recordings whirl backward there); and of the
  bearings that whirl forward, with the whirl index negated as one inverted probe or an x/y swap does, the share
  it would wrongly take for the machine's (the rest stay left out, as before).
- **The probe frame** (``centreline_frame_turned``, ``models.status``): the share of recordings it fires on as
  they are, against the training's overall attitude (``attitude_offset_reference_deg_``) and against the nearest
  training machines' (``MisalignmentModel.attitude_reference_deg``); and with the probes' frame turned by −60°,
  +60° and 90° at every bearing (the shares it should fire on).

Last, the cost of one nearest-neighbour query (each check makes one per verdict). The figures are in docs/checks.md ("A backward 1X at one bearing", "The probe frame").
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

TURNS_DEG = (-60.0, 60.0, 90.0)


def turned(names: list[str], row: np.ndarray, deg: float) -> np.ndarray:
    """``row`` with the centreline of every bearing turned by ``deg`` (the probes' frame turned the other way)."""
    out = row.copy()
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    for b in range(1, 10):
        if f"b{b}_centre_x_per_c" in names:
            jx, jy = names.index(f"b{b}_centre_x_per_c"), names.index(f"b{b}_centre_y_per_c")
            out[jx], out[jy] = c * row[jx] - s * row[jy], s * row[jx] + c * row[jy]
    return out


def measure(model, names: list[str], X: np.ndarray) -> dict:
    from rotordiag.features import REVERSE_WHIRL_INDEX
    from rotordiag.models.checks.backward_whirl import backward_as_trained
    from rotordiag.models.status import _probe_frame_reasons

    real, inverted = [], []
    for row in X:
        for b in (2, 3):
            j = names.index(f"b{b}_1x_whirl_index")
            wi = row[j]
            if not np.isfinite(wi):
                continue
            if wi < REVERSE_WHIRL_INDEX:
                seen = backward_as_trained(model, names, row, b)
                real.append(bool(seen and seen.as_trained))
            elif wi > -REVERSE_WHIRL_INDEX:
                flipped = row.copy()
                flipped[j] = -wi
                seen = backward_as_trained(model, names, flipped, b)
                inverted.append(bool(seen and seen.as_trained))
    overall = model.attitude_offset_reference_deg_

    def fires(r: np.ndarray, reference) -> bool:
        return bool(_probe_frame_reasons(names, r, reference_deg=reference))

    frame = {"as recorded": (np.mean([fires(r, overall) for r in X]),
                             np.mean([fires(r, model.attitude_reference_deg(r)) for r in X]))}
    for deg in TURNS_DEG:
        rows = [turned(names, r, deg) for r in X]
        frame[f"turned {deg:+.0f}°"] = (np.mean([fires(r, overall) for r in rows]),
                                        np.mean([fires(r, model.attitude_reference_deg(r)) for r in rows]))
    return {"n": len(X), "real": real, "inverted": inverted, "frame": frame}


def _share(flags: list[bool]) -> str:
    return f"{np.mean(flags):.0%} of {len(flags)}" if flags else "–"


def main(argv: list[str] | None = None) -> int:
    from rotordiag.models.dataset import load_feature_table
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.registry import shipped_registry_dir

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("datasets", nargs="+", type=Path)
    ap.add_argument("--registry", type=Path, default=None)
    ap.add_argument("--n", type=int, default=200, help="rows per dataset")
    args = ap.parse_args(argv)
    bundle = load_bundle(args.registry or shipped_registry_dir())
    model = bundle.model
    names = list(model.feature_names_)
    print(f"model {bundle.version}\n")
    print("| dataset | rows | backward 1X at bearing 2/3 read as the machine's | forward 1X with an inverted probe "
          "taken for the machine's | frame check fires: overall reference → nearest machines' |")
    print("|---|---|---|---|---|")
    for path in args.datasets:
        t = load_feature_table(path)
        X = t.X[:, [list(t.feature_names).index(n) for n in names]][: args.n]
        m = measure(model, names, X)
        frame = "; ".join(f"{k} {a:.0%} → {b:.0%}" for k, (a, b) in m["frame"].items())
        print(f"| {path.stem} | {m['n']} | {_share(m['real'])} | {_share(m['inverted'])} | {frame} |")
    rows = [r for r in X[:50]]
    t0 = time.perf_counter()
    for r in rows:
        model.attitude_reference_deg(r)
    per_query_ms = 1e3 * (time.perf_counter() - t0) / len(rows)
    print(f"\none nearest-neighbour query ({model.ood_.reference_.shape[0]} reference rows × "
          f"{model.ood_.reference_.shape[1]} columns): {per_query_ms:.2f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
