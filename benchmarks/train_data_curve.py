"""What would lift the verdict on shaft trains: more training trains, or features across bearings? (issue 48)

    .venv/bin/python benchmarks/train_data_curve.py --train-data DIR --data DIR [--curve 0.25,0.5,1] [--ablation]
        [--without-across] [--capacity DEFAULT_DATA]

``--train-data``: the four shaft-train training parts (``models/trains/dataset_trains_*.toml`` generated with other
seeds, as for ``benchmarks/train_verdict.py --train-data``); ``--data``: the judged trains (the same families, other
machines). Two measurements, each printed as a Markdown table:

- ``--curve``: models trained with the shipped recipe (``models/default/train.toml``, ``train_verdict.train_without``)
  on a seeded random fraction of the training trains alone (whole machines: all rows of a sample together), each
  judged as the verdict is given (``train_verdict.judge``, speed and clearance stated): Spearman and mean absolute
  error of the Δ estimate, confident answers and how many are in the true band, false alarms (healthy trains given
  any misalignment class, any status). Minutes per fraction. They are trained with the columns across
  bearings (``features._across``), which the shipped ``train.toml`` excludes; ``--without-across`` keeps its exclusion.
- ``--ablation``: a plain gradient-boosted Δ regressor (two seeds, averaged) on the training trains' feature rows,
  scored on the judged trains' rows, without and with the columns across bearings (``features._across``: the
  ratio and difference of the journals' static eccentricities and positions between neighbouring bearings — the
  load one bearing takes from another when the coupling is offset, with the oil film's common factors divided
  out — and the 1X / 2X orbit ratios), quantities a tree can only approximate from the per-bearing columns.
  Judged on every family (trained on every family) and on each family trained on the others (a design the
  regressor never saw). Under a minute.
- ``--capacity DEFAULT_DATA`` (the seventeen parts of ``make default-model``): is the Δ estimate limited by what the
  recordings carry or by the shipped recipe? A plain boosted Δ regressor on the shipped training table (every part,
  augmented as ``train.toml``; the rows with all four centrelines, as the judged recordings have; ``bench_learning_curve.default_training_table``) at the shipped
  regressor's settings and with more capacity; then, on the training trains' own rows (no augmentation), one
  regressor per family, and one per family and coupling (the coupling known, as a plant's shaft line states it).
  Each judged on the judged trains' rows (no augmentation: the recordings as stored), per coupling: mean absolute
  error and standard deviation of the Δ error, and the ROC AUC of healthy against Δ ≥ 0.15. About two minutes.

Nothing here changes the shipped model; the figures are in docs/train-verdict.md ("What would lift it").
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import train_verdict as tv  # noqa: E402  (benchmarks/ on sys.path)
from train_targets import MODERATE_DELTA  # noqa: E402

CONFIG = ROOT / "models" / "default" / "train.toml"
BANDS = ("aligned", "slight", "moderate", "severe")


def across_columns() -> tuple[str, ...]:
    """The names of the feature columns across bearings (``features._across``)."""
    from rotordiag.features import ACROSS_FEATURES

    return ACROSS_FEATURES


def config_with_across(root: Path) -> Path:
    """The shipped configuration with the columns across bearings no longer excluded, written under ``root``."""
    from rotordiag.models.config import TrainConfig

    text = CONFIG.read_text()
    line = next((x for x in text.splitlines() if x.startswith("exclude = ")), None)
    if line is None or "centre_ecc_b?_b?_ratio" not in line:
        raise SystemExit(f"{CONFIG}: no exclude line naming the columns across bearings; update config_with_across")
    path = root / "train_with_across.toml"
    path.write_text(text.replace(line, 'exclude = ["b?_[xy]_[123]x_phase_deg"]'))
    assert not set(across_columns()) & set(TrainConfig.from_file(path).exclude_features)
    return path


def tv_edges() -> list[float]:
    """The band edges of the shipped configuration (``[bands] edges``)."""
    from rotordiag.models.config import TrainConfig

    return list(TrainConfig.from_file(CONFIG).bands.edges)


def curve(fractions: list[float], train_data: Path, data: Path, seed: int, config: Path = CONFIG) -> None:
    from scipy.stats import spearmanr

    table, fams = tv.family_tables(train_data, config)
    samples = tv.read_samples(data)
    row_keys = list(zip(fams.tolist(), np.asarray(table.sample_index).tolist()))     # a machine's key per row
    keys = sorted(set(row_keys))
    order = np.random.default_rng(seed).permutation(len(keys))
    edges = np.asarray(tv_edges())
    print("| fraction | training trains (keys) | rows | Spearman Δ | Δ MAE | confident | of them in the true band | "
          "false alarms | wall s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for frac in fractions:
        keep = {keys[i] for i in order[: int(round(frac * len(keys)))]}
        mask = np.array([k in keep for k in row_keys])
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as td:
            bundle = tv.train_without(table, np.where(mask, fams, "__left_out__"), "__left_out__", config, Path(td))
            outs = tv.judge(bundle, samples, "speed and clearance stated")
        d = np.array([o.delta for o in outs])
        e = np.array([o.delta_model for o in outs])
        conf = [o for o in outs if o.status == "confident"]
        right = sum(BANDS.index(o.severity) == int(np.searchsorted(edges, o.delta, side="right")) for o in conf)
        fa = np.mean([o.model_class != "aligned" for o in outs if o.delta == 0])
        print(f"| {frac:g} | {len(keep)} | {int(mask.sum())} | {spearmanr(d, e).correlation:.3f} | "
              f"{np.nanmean(np.abs(d - e)):.4f} | {len(conf)} of {len(outs)} | {right} | {fa:.1%} | "
              f"{time.perf_counter() - t0:.0f} |", flush=True)


def ablation(train_data: Path, data: Path) -> None:
    from scipy.stats import spearmanr
    from sklearn.ensemble import HistGradientBoostingRegressor

    tr, fam_tr = tv.family_tables(train_data, CONFIG)
    te, fam_te = tv.family_tables(data, CONFIG)
    across = set(across_columns())
    keep = np.array([n not in across for n in tr.feature_names])
    print(f"training rows {len(tr.misalignment)}, judged rows {len(te.misalignment)}; {len(across)} columns "
          f"across bearings: {', '.join(across_columns())}")
    print("| judged | trained on | features | Spearman Δ | Δ MAE |")
    print("|---|---|---|---|---|")
    held = [("every family", "every family", np.ones(len(fam_tr), bool), np.ones(len(fam_te), bool))]
    held += [(f, "the other families", fam_tr != f, fam_te == f) for f in sorted(set(fam_te.tolist()))]
    for judged, trained, m_tr, m_te in held:
        for label, Xtr, Xte in (("without across bearings", tr.X[:, keep], te.X[:, keep]),
                                ("with across bearings", tr.X, te.X)):
            scores = []
            for seed in (0, 1):
                reg = HistGradientBoostingRegressor(max_iter=400, learning_rate=0.05, max_leaf_nodes=31,
                                                    random_state=seed)
                p = reg.fit(Xtr[m_tr], tr.misalignment[m_tr]).predict(Xte[m_te])
                y = te.misalignment[m_te]
                scores.append((spearmanr(y, p).correlation, np.mean(np.abs(y - p))))
            s = np.mean(scores, axis=0)
            print(f"| {judged} | {trained} | {label} | {s[0]:.3f} | {s[1]:.4f} |", flush=True)




def coupling_errors(y_true: np.ndarray, y_pred: np.ndarray, mechanism: np.ndarray,
                    couplings: tuple[str, ...] | None = None) -> dict[str, tuple[float, ...]]:
    """Per coupling (its misaligned rows and the healthy ones; ``couplings``, default every one in ``mechanism``):
    mean absolute Δ error, its standard deviation, and the ROC AUC of the estimate for healthy (Δ = 0) against
    Δ ≥ :data:`MODERATE_DELTA`."""
    from sklearn.metrics import roc_auc_score

    out = {}
    for coupling in couplings or sorted(set(mechanism.tolist()) - {"aligned"}):
        sel = np.isin(mechanism, [coupling, "aligned"])
        err = y_pred[sel] - y_true[sel]
        told = (y_true[sel] == 0.0) | (y_true[sel] >= MODERATE_DELTA)
        auc = roc_auc_score(y_true[sel][told] >= MODERATE_DELTA, y_pred[sel][told])
        out[coupling] = (float(np.mean(np.abs(err))), float(np.std(err)), float(auc))
    return out


def capacity(default_data: Path, train_data: Path, data: Path) -> None:
    import bench_learning_curve as blc
    from sklearn.ensemble import HistGradientBoostingRegressor

    from rotordiag.models.config import TrainConfig

    base, shipped = blc.default_training_table(default_data)       # augmented as train.toml, its columns
    exclude = TrainConfig.from_dict(base).exclude_features
    judged, fam_te = tv.family_tables(data, None)          # the rows as stored
    trains, fam_tr = tv.family_tables(train_data, None)
    judged, trains = judged.without_features(exclude), trains.without_features(exclude)
    names = list(shipped.feature_names)
    if list(judged.feature_names) != names or list(trains.feature_names) != names:
        raise SystemExit("the judged, training and shipped tables' columns differ: extract them with one code version")
    centrelines = [names.index(f"b{b}_centre_ecc_per_c") for b in (1, 2, 3, 4)]
    four = np.isfinite(shipped.X[:, centrelines]).all(axis=1)
    mech_te, mech_tr = np.asarray(judged.mechanism, dtype=object), np.asarray(trains.mechanism, dtype=object)
    print(f"shipped table {shipped.X.shape[0]} rows ({four.sum()} with four centrelines), training trains "
          f"{trains.X.shape[0]}, judged {judged.X.shape[0]}")
    print("| regressor | trained on | coupling | Δ MAE | Δ error s.d. | AUC healthy vs Δ ≥ 0.15 | fit s |")
    print("|---|---|---|---|---|---|---|")

    def fit(rows_X, rows_y, **kw):
        return HistGradientBoostingRegressor(random_state=0, early_stopping=False, l2_regularization=1.0,
                                             min_samples_leaf=20, **kw).fit(rows_X, rows_y)

    def show(label, trained, pred, fit_s, only=None):
        errors = coupling_errors(judged.misalignment, np.clip(pred, 0.0, None), mech_te,
                                 None if only is None else (only,))
        for coupling, (mae, sd, auc) in errors.items():
            print(f"| {label} | {trained} | {coupling} | {mae:.3f} | {sd:.3f} | {auc:.3f} | {fit_s:.0f} |", flush=True)

    for label, kw in (("shipped settings: 150 × 15 leaves, rate 0.1", dict(max_iter=150, max_leaf_nodes=15)),
                      ("600 × 31 leaves, rate 0.1", dict(max_iter=600, max_leaf_nodes=31)),
                      ("1500 × 31 leaves, rate 0.05", dict(max_iter=1500, max_leaf_nodes=31, learning_rate=0.05))):
        kw.setdefault("learning_rate", 0.1)
        t0 = time.perf_counter()
        reg = fit(shipped.X[four], shipped.misalignment[four], **kw)
        show(label, "the shipped table, four centrelines", reg.predict(judged.X), time.perf_counter() - t0)
    small = dict(max_iter=300, max_leaf_nodes=15, learning_rate=0.05)
    t0 = time.perf_counter()
    pred = np.full(judged.X.shape[0], np.nan)
    for family in sorted(set(fam_te.tolist())):
        pred[fam_te == family] = fit(trains.X[fam_tr == family], trains.misalignment[fam_tr == family],
                                     **small).predict(judged.X[fam_te == family])
    show("300 × 15 leaves, rate 0.05, one per family", "the training trains", pred, time.perf_counter() - t0)
    for coupling in sorted(set(mech_tr.tolist()) - {"aligned"}):
        t0 = time.perf_counter()
        pred = np.full(judged.X.shape[0], np.nan)     # the healthy trains judged by each coupling's model in turn
        for family in sorted(set(fam_te.tolist())):
            tr = (fam_tr == family) & np.isin(mech_tr, [coupling, "aligned"])
            te = (fam_te == family) & np.isin(mech_te, [coupling, "aligned"])
            pred[te] = fit(trains.X[tr], trains.misalignment[tr], **small).predict(judged.X[te])
        show("300 × 15 leaves, rate 0.05, one per family and coupling", "the training trains", pred,
             time.perf_counter() - t0, only=coupling)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--train-data", type=Path, required=True)
    ap.add_argument("--data", type=Path, required=True)
    ap.add_argument("--curve", type=str, default="", help="comma-separated fractions of the training trains")
    ap.add_argument("--ablation", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--without-across", action="store_true",
                    help="--curve with the shipped exclusion of the columns across bearings")
    ap.add_argument("--capacity", type=Path, default=None, metavar="DEFAULT_DATA",
                    help="the Δ regressor's capacity and per-family models (the seventeen parts of make default-model)")
    args = ap.parse_args(argv)
    if args.capacity is not None:
        capacity(args.capacity, args.train_data, args.data)
    if args.ablation:
        ablation(args.train_data, args.data)
    if args.curve:
        with tempfile.TemporaryDirectory() as td:
            config = CONFIG if args.without_across else config_with_across(Path(td))
            curve([float(x) for x in args.curve.split(",")], args.train_data, args.data, args.seed, config)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
