"""Does more data or a bigger model lower the Δ error? A learning curve and model-size variants.

    .venv/bin/python benchmarks/bench_learning_curve.py [--data data/default] [--n 48]
        [--cache /tmp/rotordiag_bench_robustness] [--variants all]

Trains ``MisalignmentModel`` s with ``models.train.fit_final`` on the shipped model's training parts
(``make default-model`` writes them to ``data/default``; the feature cache next to them is used) and the
shipped ``models/default/train.toml``, changed per variant (:data:`VARIANTS`: a fraction of the plants,
chosen with a fixed seed, more / larger trees, or a different share of rows trained without the clearance
features). Each is scored on the robustness report's recordings (``bench_robustness``: the clean base sets of
seeds 815 and 816, the far plants of seed 815 and the ``clearance unknown`` recordings of seed 815,
simulated or read from ``--cache``): the Δ estimate's mean absolute error on each mechanism's
misaligned cases and the classifier's macro-F1 per mechanism. The shipped model is scored beside them.
It answers what a per-mechanism F1 target asks for (docs/models-history.md, "What would a rigid macro-F1 of
0.95 take?"). Several minutes per variant on two cores.
"""
from __future__ import annotations

import argparse
import copy
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_robustness as br  # noqa: E402

#: variant name → (fraction of the training plants, changes to train.toml)
VARIANTS: dict[str, tuple[float, dict]] = {
    "25 % of the plants": (0.25, {}),
    "50 % of the plants": (0.5, {}),
    "all plants": (1.0, {}),
    "300 iterations": (1.0, {"classifier": {"max_iter": 300}, "regressor": {"max_iter": 300}}),
    "400 iterations, learning rate 0.05, 31 leaves": (1.0, {
        "classifier": {"max_iter": 400, "learning_rate": 0.05, "max_leaf_nodes": 31},
        "regressor": {"max_iter": 400, "learning_rate": 0.05}}),
    # one classifier and Δ regressor for both clearance cases (v0001: the clearance features blanked in half the
    # rows) against one model per case: every row with its clearance features (for recordings that state the
    # clearance) / none with them (for those that do not); the shipped model has a pair per case (clearance_heads)
    "one pair for both clearance cases (dropout 0.5, as v0001)": (1.0, {"features": {"clearance_heads": False}}),
    "clearance dropout 0 (every row with the clearance)": (
        1.0, {"features": {"clearance_heads": False, "clearance_dropout": 0.0}}),
    "clearance dropout 1 (no row with the clearance)": (
        1.0, {"features": {"clearance_heads": False, "clearance_dropout": 1.0}}),
}
#: (simulated set, seed, bench_robustness condition, column heading) scored: the report's ``clean``, ``far plants``
#: and ``clearance unknown`` rows (the same measurement, each with its own noise draws)
EVAL_SETS: tuple[tuple[str, int, str, str], ...] = (
    ("base", 815, "clean", "base 815"), ("base", 816, "clean", "base 816"),
    ("far", 815, "far plants (÷2…×2)", "far 815"), ("base", 815, "clearance unknown", "base 815, clearance unknown"))
PLANT_SEED = 1


def merged(base: dict, changes: dict) -> dict:
    """``base`` with ``changes`` applied (nested tables merged, not replaced)."""
    out = copy.deepcopy(base)
    for k, v in changes.items():
        out[k] = merged(out.get(k, {}), v) if isinstance(v, dict) else v
    return out


def plant_subset(plant_id: np.ndarray, fraction: float, seed: int = PLANT_SEED) -> np.ndarray:
    """Rows of a seeded ``fraction`` of the plants (whole plants, so augmented copies stay together)."""
    plants = np.unique(plant_id)
    keep = np.random.default_rng(seed).permutation(plants)[:int(fraction * len(plants))]
    return np.isin(plant_id, keep)


def default_training_table(data: Path):
    """(train.toml as a dict, feature table) of the shipped model's training parts in ``data`` (the Makefile's
    ``DEFAULT_PARTS``, written there by ``make default-model``; features from the cache next to them)."""
    from rotordiag.models.config import TrainConfig
    from rotordiag.models.dataset import load_feature_tables

    text = (ROOT / "Makefile").read_text()
    parts = text.split("DEFAULT_PARTS = ", 1)[1].splitlines()[0].split()
    paths = [data / f"{p}.h5" for p in parts]
    missing = [str(p) for p in paths if not p.exists()]
    if missing:
        raise SystemExit(f"training parts missing ({', '.join(missing[:3])} …): run `make default-model` first")
    base = tomllib.loads((ROOT / "models" / "default" / "train.toml").read_text())
    cfg = TrainConfig.from_dict(base)
    return base, load_feature_tables(paths, cache=True, augment=cfg.augment).without_features(cfg.exclude_features)


def eval_rows(names: list[str], n: int, cache: Path) -> dict[tuple[str, int, str], tuple[np.ndarray, ...]]:
    """Feature rows (X, Δ, mechanism) of each :data:`EVAL_SETS` set, measured as in bench_robustness (the
    clearance stated only where the condition gives it)."""
    from rotordiag.features import ProbeChannel, Recording, extract_features
    from rotordiag.models.predict import feature_vector

    out = {}
    for sim_set, seed, cond_name, _ in EVAL_SETS:
        cond = next(c for c in br.CONDITIONS if c.name == cond_name)
        cases, disps = br.simulate_set(sim_set, n, seed, cache)
        X, delta, mech = [], [], []
        for i, (c, d) in enumerate(zip(cases, disps)):
            if d is None:
                continue
            w = br.measure(d, c["speed_rpm"], cond, br.measurement_rng(cond, seed, i))
            chans = [ProbeChannel(b, a, "um", w[2 * k + j]) for k, b in enumerate(cond.bearings)
                     for j, a in enumerate(br.ANGLES_DEG)]
            clearance_um = c["plant"]["clearance_m"] * 1e6 if cond.clearance_given else None
            fr = extract_features(Recording(sample_rate_hz=br.FS_HZ, channels=chans, speed_rpm=c["speed_rpm"],
                                            clearance_um=clearance_um))
            X.append(feature_vector(names, fr)[0])
            delta.append(c["misalignment"])
            mech.append(c["label_mechanism"])
        out[(sim_set, seed, cond_name)] = (np.array(X), np.array(delta), np.array(mech, dtype=object))
    return out


def score(model, rows) -> dict[tuple[str, int, str], dict[str, tuple[float, float]]]:
    """Per set and mechanism: (Δ MAE on its misaligned cases, macro-F1 with the aligned ones)."""
    from sklearn.metrics import f1_score

    edges = np.asarray(model.bands_.edges, dtype=float)
    out = {}
    for key, (X, delta, mech) in rows.items():
        cls = model.band_index(model.predict_proba(X), X)
        point = model.predict_misalignment(X)[0]
        truth = np.searchsorted(edges, delta, side="right")
        per = {}
        for m in br.MECHANISMS:
            sel = (mech == m) | (delta == 0)
            per[m] = (float(np.mean(np.abs(point[mech == m] - delta[mech == m]))),
                      float(f1_score(truth[sel], cls[sel], average="macro", labels=np.unique(truth[sel]))))
        out[key] = per
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--data", type=Path, default=ROOT / "data" / "default")
    ap.add_argument("--n", type=int, default=48)
    ap.add_argument("--cache", type=Path, default=br.DEFAULT_CACHE)
    ap.add_argument("--variants", default="all", help="comma-separated names of VARIANTS, or 'all'")
    args = ap.parse_args(argv)

    from rotordiag.models.config import TrainConfig
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.train import fit_final

    base, table = default_training_table(args.data)
    rows = eval_rows(list(table.feature_names), args.n, args.cache)
    wanted = list(VARIANTS) if args.variants == "all" else [v.strip() for v in args.variants.split(",")]
    results = {"shipped v0001": score(load_bundle(ROOT / "models" / "default_registry").model, rows)}
    n_plants = {"shipped v0001": None}
    for name in wanted:
        fraction, changes = VARIANTS[name]
        sub = table.subset(plant_subset(table.plant_id, fraction)) if fraction < 1 else table
        t0 = time.perf_counter()
        model = fit_final(sub, TrainConfig.from_dict(merged(base, changes)))
        print(f"{name}: {len(sub)} rows, fitted in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
        results[name], n_plants[name] = score(model, rows), len(np.unique(sub.plant_id))
    sets = [heading for *_, heading in EVAL_SETS]
    print("Δ MAE on the misaligned cases, " + " / ".join(br.MECHANISMS) + " (macro-F1 rigid)\n")
    print("| model | plants | " + " | ".join(sets) + " |")
    print("|---|---|" + "---|" * len(sets))
    for name, res in results.items():
        cells = [" / ".join(f"{res[k][m][0]:.3f}" for m in br.MECHANISMS) + f" ({res[k]['rigid'][1]:.2f})"
                 for k in rows]
        print(f"| {name} | {n_plants[name] or '–'} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
