"""Train, evaluate and register a model from a labelled feature table."""
from __future__ import annotations

import tempfile
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.base import clone

from .config import TrainConfig
from .direction import fit_direction_heads
from .evaluate import METHODS, evaluate, plot_report
from .families import families_of_specs, specs_of_meta
from .registry import TRUSTED_TYPES, Registry, dumps_json
from .status import DEFAULT_POLICY
from .table import FeatureTable


def metrics_summary(report: dict) -> dict:
    """The headline figures of a report, for the model card."""

    def pick(r: dict) -> dict:
        out: dict[str, Any] = {}
        for m in METHODS:
            if m in r:
                out[m] = {k: r[m].get(k) for k in ("macro_f1", "ece", "delta_mae", "spearman")}
                out[m]["recall"] = r[m].get("recall")
        if "model" in r and out.get("model") is not None:
            out["model"]["interval_coverage"] = r["model"].get("interval_coverage")
            out["model"]["ood_flag_rate"] = r["model"].get("ood_flag_rate")
        out["n_rows"] = r.get("n_rows")
        return out

    res = report["results"]
    return {
        "held_out": "GroupKFold over plant_id (out-of-fold)",
        "per_mechanism": {k: pick(v) for k, v in res["mechanism"].items()},
        "per_speed_band_rpm": {k: pick(v) for k, v in res["speed_band_rpm"].items()},
        "all_mixed_average": pick(res["all"]["all"]),
        "clearance_unknown": {k: pick(v) for k, v in res.get("clearance_unknown", {}).items()},
        "targets": report["targets"],
    }


def fit_final(table: FeatureTable, config: TrainConfig):
    """The deployable model: fitted on every row of ``table`` (the clearance features handled as in
    the evaluation: ``config.clearance_dropout`` and ``config.clearance_heads``), with the offset-direction heads
    (``models.direction``) as ``direction_heads_`` when ``config.direction_heads`` and the table records every
    row's offset direction."""
    model = config.make_model(table.feature_names, clearance_seed=config.seed + 999)
    model.fit(table.X, table.misalignment, groups=table.plant_id)
    if config.direction_heads and table.has_direction_labels:
        assert table.offset_angle_rad is not None  # has_direction_labels
        try:
            model.direction_heads_ = fit_direction_heads(
                table.X, table.feature_names, table.misalignment, table.offset_angle_rad, table.angular_mrad,
                table.plant_id, clone(model.regressor).set_params(monotonic_cst=None))
        except ValueError as exc:          # too few rows with the centreline: the model says it has no direction
            model.direction_note_ = str(exc)
    return model


def direction_card(model: Any) -> dict[str, Any]:
    """The card's ``direction`` entry: whether the model estimates the offset's direction and angular offset, and
    on how many rows and plants its heads were fitted."""
    d = getattr(model, "direction_heads_", None)
    if d is None:
        return {"estimated": False, "why_not": getattr(model, "direction_note_", None)
                or "trained without direction labels or without [direction] heads"}
    return {"estimated": True, "angular": d["heads"].get("angular_mrad") is not None, "n_rows": d["n_rows"],
            "n_plants": d["n_plants"], "interval_level": d["interval_level"],
            "angular_range_mrad": d["angular_range_mrad"]}


def train_and_register(
    table: FeatureTable,
    config: TrainConfig,
    registry: Registry,
    *,
    activate: bool = True,
    card_extra: Mapping[str, Any] | None = None,
) -> tuple[str, dict]:
    """Evaluate on held-out plants, fit on all rows, register model + card + report.

    Parameters
    ----------
    table : FeatureTable
        ``table.meta`` may carry ``dataset_path``, ``dataset_hash``, ``dataset_spec``,
        ``plant_family`` and ``skipped`` (recorded in the card).
    config : TrainConfig
    registry : Registry
    activate : bool
        Make the new version active.
    card_extra : mapping, optional
        More card fields.

    Returns
    -------
    (version, report)
    """
    table = table.without_features(config.exclude_features)
    t0 = time.perf_counter()
    report, oof = evaluate(table, config)
    t1 = time.perf_counter()
    model = fit_final(table, config)
    fit_s = time.perf_counter() - t1
    report["protocol"]["final_fit_time_s"] = round(fit_s, 2)
    with tempfile.TemporaryDirectory() as td:
        png = Path(td) / "report.png"
        plot_report(report, oof, table, png)
        png_bytes = png.read_bytes()
    meta = table.meta
    card = {
        "model_class": "rotordiag.models.estimators.MisalignmentModel",
        "training_data": {
            "path": meta.get("dataset_path"),
            "hash": meta.get("dataset_hash"),
            "spec": meta.get("dataset_spec"),
            "n_rows_used": len(table),
            "n_plants": int(len(np.unique(table.plant_id))),
            "skipped": meta.get("skipped", {}),
            "misalignment_range": [float(table.misalignment.min()), float(table.misalignment.max())],
            "speed_rpm_range": [float(table.speed_rpm.min()), float(table.speed_rpm.max())],
            "mechanisms": sorted(set(table.mechanism.tolist())),
        },
        "plant_family": meta.get("plant_family"),
        # the machine families it was trained on (models.families): the family guard reads them
        "training_families": families_of_specs(specs_of_meta(meta)),
        "feature_names": list(table.feature_names),
        "bands": config.bands.to_dict(),
        "interval_level": 1 - float(model.regressor_.alpha),
        "ood_threshold": float(model.ood_.threshold_),
        # the thresholds that turn the model's call into the verdict's status, stored with the model
        "decision_policy": DEFAULT_POLICY.to_dict(),
        "direction": direction_card(model),
        "envelope": None if getattr(model, "envelope_", None) is None else {
            "features": list(model.envelope_names_), "margin_spreads": float(model.envelope_.margin_),
            "held_out_flag_rate": float(model.envelope_.calibration_flag_rate_)},
        "metrics": metrics_summary(report),
        "train_config": config.to_dict(),
        "timing_s": {"evaluation": round(t1 - t0, 2), "final_fit": round(fit_s, 2)},
        "trusted_types": list(TRUSTED_TYPES),
        **dict(card_extra or {}),
    }
    version = registry.register(
        model, card,
        extra_files={"report.json": dumps_json(report), "report.png": png_bytes},
        activate=activate,
    )
    return version, report
