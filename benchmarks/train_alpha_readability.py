"""Can the angular offset α be read from a shaft train's vibration at all? A plain regressor's answer.

    .venv/bin/python benchmarks/train_alpha_readability.py --train-data data/trains_more --data data/trains

A gradient-boosted regressor (scikit-learn's ``HistGradientBoostingRegressor``, 300 iterations, seed 0) on every
feature of the misaligned training trains (``trains_2pole.h5``, ``trains_4pole.h5`` of ``--train-data``: the shipped
model's parts, α uniform within ±0.04 mrad) predicts α, and Δ beside it, for the misaligned judged trains of
``--data`` (``models/trains/``, machines it never saw). Prints the Spearman correlation and the mean absolute error
against always answering 0. The shipped model gives no α (``angular_not_trained``); docs/models.md quotes this.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr
from sklearn.ensemble import HistGradientBoostingRegressor

PARTS = ("trains_2pole", "trains_4pole")


def _table(folder: Path):
    from rotordiag.models.dataset import load_feature_table
    from rotordiag.models.table import FeatureTable

    return FeatureTable.concat([load_feature_table(folder / f"{p}.h5") for p in PARTS])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--train-data", type=Path, default=Path("data/trains_more"))
    ap.add_argument("--data", type=Path, default=Path("data/trains"))
    args = ap.parse_args(argv)
    train, judged = _table(args.train_data), _table(args.data)
    if train.angular_mrad is None or judged.angular_mrad is None:
        raise SystemExit("the datasets record no angular offset (parameters/angular_misalignment_mrad)")
    cols = [list(judged.feature_names).index(n) for n in train.feature_names]
    X = judged.X[:, cols]
    print(f"{train.X.shape[0]} training rows, {X.shape[0]} judged; α within "
          f"{np.nanmin(train.angular_mrad):+.3f}…{np.nanmax(train.angular_mrad):+.3f} mrad")
    for name, y_train, y_true in (("α (mrad)", train.angular_mrad, judged.angular_mrad),
                                  ("Δ", train.misalignment, judged.misalignment)):
        pred = HistGradientBoostingRegressor(max_iter=300, random_state=0).fit(train.X, y_train).predict(X)
        rho = spearmanr(pred, y_true)[0]
        mae, mae0 = float(np.mean(np.abs(pred - y_true))), float(np.mean(np.abs(y_true)))
        print(f"{name}: Spearman {rho:+.2f}, MAE {mae:.4f} (always 0: {mae0:.4f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
