"""The two baselines every model is compared with, both on the 2X/1X amplitude ratio.

1. :class:`RuleOfThumb` — the field rule "2X > 0.5 · 1X ⇒ misaligned", with a severity
   mapping on the same ratio. Default cuts (0.5, 1.0, 2.0) for the four default bands:

   ====================  =========
   2X/1X                 verdict
   ====================  =========
   < 0.5                 aligned
   0.5 – 1.0             slight
   1.0 – 2.0             moderate
   ≥ 2.0                 severe
   ====================  =========

   (2X above half of 1X is the usual alarm; 2X ≥ 1X and ≥ 2 × 1X are the usual
   "significant" and "severe" marks in vibration-analysis practice.) Nothing is fitted.
2. :class:`RatioThresholdClassifier` — the best thresholds on the same ratio fitted on
   the training set: one cut per band boundary (for two bands this is the single
   best threshold), chosen to maximise the training macro-F1. It is the strongest
   classifier that uses 2X/1X alone.

The ratio of a row is the largest 2X/1X over the probes named by the configuration
(:func:`ratio_column`): the rule fires when any probe shows it.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from ._patterns import name_mask
from ._search import coordinate_ascent

DEFAULT_RATIO_PATTERNS: tuple[str, ...] = ("b?_[xy]_2x_1x_ratio",)
DEFAULT_RULE_CUTS: tuple[float, ...] = (0.5, 1.0, 2.0)


def match_features(names: Sequence[str], patterns: Sequence[str]) -> list[int]:
    """Indices of the feature names that match any of the glob ``patterns``."""
    return np.flatnonzero(name_mask(names, patterns)).tolist()


def ratio_column(X: np.ndarray, names: Sequence[str], patterns: Sequence[str] = DEFAULT_RATIO_PATTERNS) -> np.ndarray:
    """Per-row maximum over the 2X/1X ratio features (NaN where all are missing).

    Raises
    ------
    ValueError
        If no feature name matches ``patterns``.
    """
    cols = match_features(names, patterns)
    if not cols:
        raise ValueError(
            f"baselines.ratio_features: no feature matches {list(patterns)}; "
            f"set it to the 2X/1X feature names (have e.g. {list(names)[:8]})"
        )
    sub = np.asarray(X, dtype=float)[:, cols]
    out = np.full(sub.shape[0], np.nan)
    ok = ~np.all(np.isnan(sub), axis=1)
    out[ok] = np.nanmax(sub[ok], axis=1)
    return out


class RuleOfThumb:
    """Fixed-cut severity from the 2X/1X ratio (nothing fitted).

    Parameters
    ----------
    names : sequence of str
        Band names, smallest Δ first.
    cuts : sequence of float
        ``len(names) - 1`` increasing ratio cuts (lower-inclusive).
    """

    def __init__(self, names: Sequence[str], cuts: Sequence[float] = DEFAULT_RULE_CUTS) -> None:
        cuts = tuple(float(c) for c in cuts)
        if len(cuts) != len(names) - 1 or any(b <= a for a, b in zip(cuts, cuts[1:])):
            raise ValueError(
                f"baselines.rule_cuts: need {len(names) - 1} increasing cuts for bands {list(names)}, got {list(cuts)}"
            )
        self.names = tuple(names)
        self.cuts = cuts

    def predict(self, ratio: np.ndarray) -> np.ndarray:
        """Band name per row; a missing ratio gives the first band (no alarm)."""
        r = np.nan_to_num(np.asarray(ratio, dtype=float), nan=-np.inf)
        return np.asarray(self.names, dtype=object)[np.searchsorted(self.cuts, r, side="right")]


class RatioThresholdClassifier(ClassifierMixin, BaseEstimator):
    """Ordered thresholds on one feature, fitted for training macro-F1.

    Parameters
    ----------
    classes : sequence or None
        Class labels in order of increasing feature value; ``None`` → sorted unique ``y``.
    n_candidates : int, default=64
        Candidate cuts: this many quantiles of the training feature.
    n_passes : int, default=4
        Coordinate-ascent passes over the cuts.

    Attributes
    ----------
    classes_ : ndarray
    thresholds_ : ndarray of shape (n_classes - 1,)
    """

    def __init__(self, classes: Sequence | None = None, n_candidates: int = 64, n_passes: int = 4) -> None:
        self.classes = classes
        self.n_candidates = n_candidates
        self.n_passes = n_passes

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.allow_nan = True
        return tags

    def fit(self, X, y) -> RatioThresholdClassifier:
        """Fit the cuts. ``X`` has one column (the ratio); NaN rows count as below every cut."""
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan")
        if X.shape[1] != 1:
            raise ValueError(f"X: needs exactly one column (the 2X/1X ratio), got {X.shape[1]}")
        self.classes_ = np.asarray(self.classes if self.classes is not None else np.unique(y), dtype=object)
        k = len(self.classes_)
        if k < 2:
            raise ValueError("y: need at least two classes")
        x = np.nan_to_num(X[:, 0], nan=-np.inf)
        finite = x[np.isfinite(x)]
        cand = np.unique(np.quantile(finite, np.linspace(0, 1, self.n_candidates))) if finite.size else np.zeros(1)
        lookup = {c: i for i, c in enumerate(self.classes_)}
        try:
            yi = np.array([lookup[v] for v in y])
        except KeyError as exc:
            raise ValueError(f"y: label {exc.args[0]!r} is not in classes {list(self.classes_)}") from None

        def score(th: np.ndarray) -> float:
            # Macro-F1 from the confusion counts (same as sklearn's, much faster here).
            pi = np.searchsorted(th, x, side="right")
            cm = np.bincount(yi * k + pi, minlength=k * k).reshape(k, k)
            tp = np.diag(cm).astype(float)
            denom = cm.sum(axis=0) + cm.sum(axis=1)
            f1 = np.divide(2 * tp, denom, out=np.zeros(k), where=denom > 0)
            return float(f1[cm.sum(axis=1) > 0].mean())

        # Start from cuts that reproduce the class proportions, then coordinate ascent.
        props = np.cumsum(np.bincount(yi, minlength=k) / len(yi))[:-1]
        th = np.quantile(finite, np.clip(props, 0, 1)) if finite.size else np.zeros(k - 1)
        th = np.maximum.accumulate(th)
        def between_neighbours(j: int, cur: np.ndarray) -> np.ndarray:
            lo = cur[j - 1] if j > 0 else -np.inf
            hi = cur[j + 1] if j < k - 2 else np.inf
            return cand[(cand >= lo) & (cand <= hi)]

        th, best = coordinate_ascent(score, th, between_neighbours, n_passes=self.n_passes, tol=1e-12)
        self.thresholds_ = th
        self.train_macro_f1_ = float(best)
        return self

    def predict(self, X) -> np.ndarray:
        check_is_fitted(self, "thresholds_")
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan")
        x = np.nan_to_num(X[:, 0], nan=-np.inf)
        return self.classes_[np.searchsorted(self.thresholds_, x, side="right")]
