"""Classification, regression and calibration metrics used by the evaluation report."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.stats import spearmanr
from sklearn.metrics import confusion_matrix, f1_score, recall_score


def expected_calibration_error(
    proba: np.ndarray, y_index: np.ndarray, n_bins: int = 10
) -> float:
    """Top-label expected calibration error.

    ECE = Σ_b (n_b / n) · |accuracy_b − mean confidence_b| over ``n_bins`` equal-width
    bins of the top probability. A method that outputs hard labels (confidence 1)
    gets ECE = 1 − accuracy.

    Parameters
    ----------
    proba : ndarray of shape (n_samples, n_classes)
    y_index : ndarray of shape (n_samples,)
        True class as a column index of ``proba``.
    """
    proba = np.asarray(proba, dtype=float)
    y_index = np.asarray(y_index)
    if proba.ndim != 2 or proba.shape[0] != y_index.shape[0]:
        raise ValueError("proba: must be (n_samples, n_classes) matching y_index")
    if proba.shape[0] == 0:
        return float("nan")
    conf = proba.max(axis=1)
    correct = (proba.argmax(axis=1) == y_index).astype(float)
    # Bin b holds confidences in (b/n_bins, (b+1)/n_bins]; confidence 0 goes to bin 0.
    bins = np.clip(np.ceil(conf * n_bins).astype(int) - 1, 0, n_bins - 1)
    ece = 0.0
    for b in range(n_bins):
        sel = bins == b
        if sel.any():
            ece += sel.mean() * abs(correct[sel].mean() - conf[sel].mean())
    return float(ece)


def classification_metrics(
    y_true: Sequence[str],
    y_pred: Sequence[str],
    names: Sequence[str],
    proba: np.ndarray | None = None,
) -> dict:
    """Macro-F1, per-class recall, confusion matrix, ECE and binary detection figures.

    ``names`` is the ordered band list; the first band is "no fault". Macro-F1 averages
    over the bands present in ``y_true`` (a band absent from a subset has no recall).
    ``proba=None`` means hard labels (confidence 1) for the ECE.
    """
    y_true_a = np.asarray(y_true, dtype=object)
    y_pred_a = np.asarray(y_pred, dtype=object)
    return _classification_metrics(y_true_a, y_pred_a, list(names), proba)


def _classification_metrics(y_true: np.ndarray, y_pred: np.ndarray, names: list[str],
                            proba: np.ndarray | None) -> dict:
    names = list(names)
    present = [n for n in names if np.any(y_true == n)]
    out: dict = {"n": int(y_true.shape[0])}
    if y_true.shape[0] == 0:
        return out
    out["macro_f1"] = float(f1_score(y_true, y_pred, labels=present, average="macro", zero_division=0))
    out["accuracy"] = float(np.mean(y_true == y_pred))
    rec = recall_score(y_true, y_pred, labels=present, average=None, zero_division=0)
    out["recall"] = {n: float(r) for n, r in zip(present, rec)}
    out["confusion_matrix"] = {
        "labels": names,
        "counts": confusion_matrix(y_true, y_pred, labels=names).tolist(),
    }
    idx = {n: i for i, n in enumerate(names)}
    yi = np.array([idx[v] for v in y_true])
    if proba is None:
        proba = np.zeros((len(y_pred), len(names)))
        proba[np.arange(len(y_pred)), [idx[v] for v in y_pred]] = 1.0
    out["ece"] = expected_calibration_error(proba, yi)
    fault_true = np.asarray(y_true != names[0], dtype=bool)
    fault_pred = np.asarray(y_pred != names[0], dtype=bool)
    det: dict = {}
    if fault_true.any():
        det["recall"] = float(np.mean(fault_pred[fault_true]))
    if (~fault_true).any():
        det["false_alarm_rate"] = float(np.mean(fault_pred[~fault_true]))
    out["detection"] = det
    return out


def regression_metrics(
    delta_true: np.ndarray,
    delta_pred: np.ndarray,
    interval: np.ndarray | None = None,
    score: np.ndarray | None = None,
) -> dict:
    """Δ MAE, Spearman rank correlation and, when given, interval coverage and width.

    ``score`` (default ``delta_pred``) is the continuous output whose rank correlation
    with Δ is reported (a baseline's 2X/1X ratio, for instance).
    """
    t = np.asarray(delta_true, dtype=float)
    p = np.asarray(delta_pred, dtype=float)
    out: dict = {}
    if t.shape[0] == 0:
        return out
    out["delta_mae"] = float(np.mean(np.abs(p - t)))
    s = p if score is None else np.asarray(score, dtype=float)
    ok = np.isfinite(s)
    if ok.sum() >= 3 and np.ptp(t[ok]) > 0 and np.ptp(s[ok]) > 0:
        out["spearman"] = float(spearmanr(t[ok], s[ok]).statistic)
    else:
        out["spearman"] = None
    if interval is not None:
        iv = np.asarray(interval, dtype=float)
        out["interval_coverage"] = float(np.mean((iv[:, 0] <= t) & (t <= iv[:, 1])))
        out["interval_mean_width"] = float(np.mean(iv[:, 1] - iv[:, 0]))
    return out
