"""How often is a confident verdict wrong by two bands or more? Out-of-fold, on held-out plants.

    .venv/bin/python benchmarks/bench_status.py [--data data/default]

Cross-validates the shipped ``models/default/train.toml`` by plant on the shipped model's training parts
(``models.evaluate.cross_validate``: 5 folds, every row predicted by a model that never saw its plant; the
parts from ``make default-model``) and counts, with the clearance given and with it blanked, the verdicts
that would be ``confident`` and are two or more bands off — a moderate misalignment called aligned is the
gross error a plant acts on wrongly. "Confident" is approximated from the model's outputs alone: top class
≥ ``CONFIDENT_MIN_PROBABILITY`` and not OOD (the sanity, scale, speed, missing-feature, 2X-signature and
class/Δ reasons of ``models.status`` are left out), then with the status rules that use only those outputs:
at most a share of probability on the bands two or more from the call (``CONFIDENT_MAX_FAR_PROBABILITY``
and the alternatives in :data:`FAR_LIMITS`), without the clearance no confident ``aligned``
(``offset_not_assessed``), and, with the shipped far-band limit, the Δ regressor's interval within one band
of the call (``far_band_interval``). About 20 minutes on two cores.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_learning_curve import ROOT, default_training_table  # noqa: E402

#: probability limits on the bands two or more from the call that are compared (None: no limit)
FAR_LIMITS: tuple[float | None, ...] = (None, 0.1, 0.15, 0.2)


def confident_errors(proba: np.ndarray, call: np.ndarray, truth: np.ndarray, ood: np.ndarray, *,
                     min_probability: float, far_limit: float | None, aligned_allowed: bool,
                     interval: np.ndarray | None = None, edges=()) -> dict[str, int]:
    """Counts of the approximately confident verdicts: ``n``, ``off2`` (two or more bands off), ``right``.
    With ``interval`` (n, 2) and the bands' ``edges``: also no Δ interval reaching two bands from the call."""
    from rotordiag.models.status import far_band_probability, interval_far_bands

    conf = (np.max(proba, axis=1) >= min_probability) & ~ood
    if far_limit is not None:
        conf &= far_band_probability(proba, call) <= far_limit
    if interval is not None:
        conf &= ~interval_far_bands(interval, call, edges)
    if not aligned_allowed:
        conf &= call > 0
    off = np.abs(call - truth)
    return {"n": int(conf.sum()), "off2": int(np.sum(conf & (off >= 2))), "right": int(np.sum(conf & (off == 0)))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--data", type=Path, default=ROOT / "data" / "default")
    args = ap.parse_args(argv)

    from rotordiag.models.config import TrainConfig
    from rotordiag.models.evaluate import cross_validate
    from rotordiag.models.status import CONFIDENT_MAX_FAR_PROBABILITY, CONFIDENT_MIN_PROBABILITY

    base, table = default_training_table(args.data)
    cfg = TrainConfig.from_dict(base)
    oof = cross_validate(table, cfg)
    names = list(cfg.bands.names)
    truth = np.searchsorted(np.asarray(cfg.bands.edges, dtype=float), table.misalignment, side="right")
    print(f"{len(table)} out-of-fold rows, {len(np.unique(table.plant_id))} plants; confident ≈ top class ≥ "
          f"{CONFIDENT_MIN_PROBABILITY:.0%} and not OOD (shipped limit on the far bands: "
          f"{CONFIDENT_MAX_FAR_PROBABILITY:.0%})\n")
    print("| clearance | limit on the far bands | aligned may be confident | Δ interval within one band | confident | "
          "two or more bands off | right |")
    print("|---|---|---|---|---|---|---|")
    edges = np.asarray(cfg.bands.edges, dtype=float)
    for label, proba, pred, interval in (("given", oof.proba, oof.pred["model"], oof.interval),
                                         ("not given", oof.proba_no_clearance, oof.pred_no_clearance,
                                          oof.interval_no_clearance)):
        if proba is None:
            continue
        call = np.array([names.index(p) for p in pred])
        for limit in FAR_LIMITS:
            for aligned_allowed in ((True,) if label == "given" else (True, False)):
                for iv in (None, interval) if limit == CONFIDENT_MAX_FAR_PROBABILITY else (None,):
                    c = confident_errors(proba, call, truth, oof.ood_flag, min_probability=CONFIDENT_MIN_PROBABILITY,
                                         far_limit=limit, aligned_allowed=aligned_allowed, interval=iv, edges=edges)
                    print(f"| {label} | {'none' if limit is None else f'{limit:.0%}'} | "
                          f"{'yes' if aligned_allowed else 'no'} | {'no rule' if iv is None else 'yes'} | {c['n']} | "
                          f"{c['off2']} ({c['off2'] / max(c['n'], 1):.1%}) | {c['right']} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
