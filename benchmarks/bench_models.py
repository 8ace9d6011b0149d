"""Benchmark of the models package: verdict latency and training time on 5,000 samples.

    .venv/bin/python benchmarks/bench_models.py [--data a.h5 b.h5] [--rows 5000] [--threads 1]

Prints absolute figures, ratios against the rule of thumb (the baseline an engineer
would use: one comparison, 2X > 0.5 · 1X), and the peak RSS.

Training rows: with ``--data`` the rows are the dataset's real feature vectors (read
through the feature cache), resampled with replacement to ``--rows`` and jittered by 1 %
so that no two rows are identical; without it, a synthetic table with the real feature
count (304 columns: 7 informative, the rest noise, 5 % NaN). Training time is the
deployable fit (classifier with its calibration folds, interval regressor, OOD scorer);
``rotordiag train`` adds the held-out evaluation, about ``n_splits`` more fits.
"""
from __future__ import annotations

import argparse
import resource
import statistics
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


def _timeit(fn, repeat: int) -> list[float]:
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return out


def _synthetic(rows: int, seed: int = 0):
    from rotordiag.features import FEATURE_NAMES

    rng = np.random.default_rng(seed)
    names = tuple(FEATURE_NAMES)
    X = rng.normal(size=(rows, len(names)))
    delta = np.where(rng.random(rows) < 0.25, 0.0, rng.uniform(0, 0.6, rows))
    r0 = rng.uniform(0.2, 0.8, rows)
    for j, n in enumerate(names):
        if n.endswith("_2x_1x_ratio"):
            X[:, j] = r0 + 1.2 * delta + rng.normal(0, 0.03, rows)
        elif n.startswith("dphase_1x_b2_b3"):
            X[:, j] = 170 * delta / (delta + 0.1) + rng.normal(0, 3, rows)
    X[rng.random(X.shape) < 0.05] = np.nan
    mech = np.where(delta == 0, "aligned", np.where(rng.random(rows) < 0.5, "pin", "rigid"))
    return X, names, delta, np.arange(rows), mech, rng.uniform(1200, 3000, rows)


def _from_data(paths, rows: int, seed: int = 0):
    from rotordiag.models.dataset import load_feature_tables

    t = load_feature_tables(paths)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, len(t), rows)
    X = t.X[idx] * (1 + 0.01 * rng.normal(size=(rows, t.X.shape[1])))
    return X, t.feature_names, t.misalignment[idx], np.arange(rows), t.mechanism[idx], t.speed_rpm[idx]


def _diagnose_plain(model, fr):
    """``models.pipeline.diagnose`` with the compiled predictor swapped for the plain model."""
    import rotordiag.models.predict as mp
    from rotordiag.models.pipeline import diagnose

    saved = mp.fast_predictor
    mp.fast_predictor = lambda m: m
    try:
        return diagnose(model, fr, clearance_um=None, top_k=5)
    finally:
        mp.fast_predictor = saved


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", nargs="*", help="dataset HDF5 file(s) for real feature rows")
    ap.add_argument("--rows", type=int, default=5000)
    ap.add_argument("--threads", type=int, default=1, help="OpenMP threads for training")
    ap.add_argument("--config", default=str(Path(__file__).resolve().parent.parent / "models/default/train.toml"))
    args = ap.parse_args()

    from threadpoolctl import threadpool_limits

    from rotordiag.models.baselines import RuleOfThumb, ratio_column
    from rotordiag.models.config import TrainConfig
    from rotordiag.models.pipeline import diagnose
    from rotordiag.models.predict import fast_predictor
    from rotordiag.models.table import FeatureTable
    from rotordiag.models.train import fit_final

    cfg = TrainConfig.from_file(args.config)
    X, names, delta, plant, mech, speed = _from_data(args.data, args.rows) if args.data else _synthetic(args.rows)
    table = FeatureTable(X, names, delta, plant, mech, speed).without_features(cfg.exclude_features)
    src = f"real features of {', '.join(args.data)} resampled" if args.data else "synthetic"
    print(f"training rows: {len(table)} × {table.X.shape[1]} features ({src}); threads {args.threads}")

    with threadpool_limits(args.threads):
        t0 = time.perf_counter()
        model = fit_final(table, cfg)
        fit_s = time.perf_counter() - t0
    print(f"training (deployable fit) on {len(table)} samples: {fit_s:.1f} s")

    rng = np.random.default_rng(1)
    rows = table.X[rng.integers(0, len(table), 200)]
    fr = SimpleNamespace(names=table.feature_names, values=rows[0])
    diagnose(model, fr)  # warm-up
    one = _timeit(lambda: diagnose(model, fr), 50)
    fast = fast_predictor(model)
    proba_fast = _timeit(lambda: fast.predict_proba(rows[:1]), 200)
    with threadpool_limits(1):
        proba_one = _timeit(lambda: model.predict_proba(rows[:1]), 50)
        plain = _timeit(lambda: _diagnose_plain(model, fr), 20)
        batch = _timeit(lambda: (model.predict_proba(rows), model.predict_misalignment(rows),
                                 model.ood_ratio(rows)), 5)
    rule = RuleOfThumb(cfg.bands.names, cfg.rule_cuts)
    rule_t = _timeit(lambda: rule.predict(ratio_column(rows[:1], table.feature_names, cfg.ratio_features)), 200)

    med = statistics.median
    print(f"diagnose() one recording's features (verdict incl. interval, OOD, top-5 features): "
          f"median {med(one) * 1e3:.2f} ms (min {min(one) * 1e3:.2f} ms)")
    print(f"  of which severity probabilities alone: median {med(proba_fast) * 1e3:.3f} ms "
          f"(scikit-learn's predict_proba on the same row: {med(proba_one) * 1e3:.2f} ms)")
    print(f"the same verdict through scikit-learn's predict methods (no compiled trees): median "
          f"{med(plain) * 1e3:.2f} ms → compiled path {med(plain) / med(one):.0f}× faster")
    print(f"batch of 200 rows (probabilities + Δ interval + OOD): median {med(batch) * 1e3:.1f} ms "
          f"= {med(batch) / 200 * 1e3:.3f} ms/row")
    print(f"rule of thumb (2X/1X cut) one row: median {med(rule_t) * 1e6:.1f} µs → diagnose() is "
          f"{med(one) / med(rule_t):.0f}× slower than the rule, per recording")
    print(f"peak RSS: {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
