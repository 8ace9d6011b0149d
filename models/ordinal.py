"""Ordinal severity classifier with monotonic constraints (issue 15, item 4).

The severity bands are ordered (aligned < slight < moderate < severe), and physics says
which way some features push them: holding everything else fixed, more 2X at the coupling
bearings never means *less* misalignment. A multiclass softmax cannot express either (and
scikit-learn's boosted trees refuse monotonic constraints for more than two classes), so
:class:`OrdinalSeverityClassifier` decomposes the problem the ordinal way (Frank & Hall
2001): one binary boosted model per band edge *k* for ``P(band ≥ k | x)``, each with the
same ``monotonic_cst``, each calibrated by a Platt map ``σ(a·s + b)`` with ``a > 0`` fitted
on out-of-fold scores (folds keep every plant on one side). The cumulative probabilities
are made non-increasing in *k* by a running minimum, and the band probabilities are their
differences.

The predicted band is the largest k whose edges 1..k all reach their thresholds — the
**median** of that distribution when every threshold is 0.5. ``max_false_alarm`` raises the
first edge's threshold until at most that share of the lowest band's rows pass it out of fold
(a false alarm on a healthy machine sends a crew; the price is recall in the second band).
Each step is non-decreasing in a feature constrained with +1 (the trees by construction,
``a > 0``, the running minimum, fixed thresholds, the sequential count), so the predicted band
never falls when such a feature grows: the property ``tests/test_models_ordinal.py`` checks.
"""
from __future__ import annotations

from numbers import Integral, Real

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.ensemble import HistGradientBoostingClassifier
from sklearn.linear_model import LogisticRegression
from sklearn.model_selection import GroupKFold, StratifiedKFold
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from ._columns import _blank, _sparse_columns
from ._search import coordinate_ascent
from ._sklearn_private import Interval

__all__ = ["OrdinalSeverityClassifier", "cumulative_to_proba"]


def cumulative_to_proba(cum: np.ndarray) -> np.ndarray:
    """Band probabilities from ``P(band ≥ k)``, k = 1..K−1 (shape (n, K−1) → (n, K)).

    The cumulative columns are first made non-increasing in k by a running minimum.
    """
    cum = np.minimum.accumulate(np.clip(np.asarray(cum, dtype=float), 0.0, 1.0), axis=1)
    n = cum.shape[0]
    upper = np.column_stack([np.ones(n), cum])
    lower = np.column_stack([cum, np.zeros(n)])
    return upper - lower


def _sigmoid(z: np.ndarray) -> np.ndarray:
    return 0.5 * (1.0 + np.tanh(0.5 * z))


class OrdinalSeverityClassifier(ClassifierMixin, BaseEstimator):
    """Cumulative-link boosted classifier for ordered classes, with monotonic constraints.

    Classes are ordered as ``numpy.unique`` sorts them (``MisalignmentModel`` passes band
    indices 0..K−1).

    Parameters
    ----------
    learning_rate, max_iter, max_leaf_nodes, min_samples_leaf, l2_regularization :
        Passed to each :class:`~sklearn.ensemble.HistGradientBoostingClassifier`.
    monotonic_cst : array-like of int of shape (n_features,) or None, default=None
        −1, 0 or +1 per feature: the direction each edge's ``P(band ≥ k)`` must move when
        the feature grows (scikit-learn's convention).
    cv : int, default=5
        Folds of the out-of-fold scores the Platt maps are fitted on (whole groups per fold
        when ``groups`` are given; reduced to the number of groups).
    max_false_alarm : float or None, default=None
        If given, the first edge's decision threshold is raised (never below 0.5) until at
        most this share of the ``healthy`` rows (default: the lowest class's) pass it *out of
        fold* (on plants the edge's model did not see): a Neyman–Pearson choice that bounds false alarms on
        healthy machines at the cost of recall in the second class.
    tune_thresholds : bool, default=False
        If true, the edges' thresholds are then chosen on the same out-of-fold probabilities to
        maximise the macro-F1 over the classes (coordinate ascent on :data:`THRESHOLD_GRID`),
        the first edge never below its ``max_false_alarm`` bound. The median rule (0.5) is
        best for accuracy under the training data's class shares; a rare band (e.g. the
        highest, whose Δ range is the narrowest) gains recall from a lower threshold.
    random_state : int, default=0

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    models_ : list of fitted HistGradientBoostingClassifier, one per edge (K − 1)
    platt_ : ndarray of shape (K − 1, 2)
        ``(a, b)`` of each edge's map ``σ(a·s + b)`` on the trees' decision value ``s``;
        ``(1, 0)`` (the trees' own probability) where calibration was not possible.
    thresholds_ : ndarray of shape (K − 1,)
        Decision threshold of each edge on its calibrated ``P(class ≥ k)`` (0.5, except the
        first edge under ``max_false_alarm`` and every edge under ``tune_thresholds``). The predicted class is the largest k whose
        edges 1..k all pass — monotone in every +1-constrained feature.
    n_iter_ : int
    """

    _parameter_constraints = {
        "learning_rate": [Interval(Real, 0, None, closed="neither")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
        "max_leaf_nodes": [Interval(Integral, 2, None, closed="left")],
        "min_samples_leaf": [Interval(Integral, 1, None, closed="left")],
        "l2_regularization": [Interval(Real, 0, None, closed="left")],
        "monotonic_cst": ["array-like", None],
        "cv": [Interval(Integral, 2, None, closed="left")],
        "max_false_alarm": [Interval(Real, 0, 0.5, closed="neither"), None],
        "tune_thresholds": ["boolean"],
        "random_state": ["random_state"],
    }

    def __init__(
        self,
        *,
        learning_rate: float = 0.1,
        max_iter: int = 150,
        max_leaf_nodes: int = 15,
        min_samples_leaf: int = 10,
        l2_regularization: float = 1.0,
        monotonic_cst=None,
        cv: int = 5,
        max_false_alarm: float | None = None,
        tune_thresholds: bool = False,
        random_state: int = 0,
    ) -> None:
        self.learning_rate = learning_rate
        self.max_iter = max_iter
        self.max_leaf_nodes = max_leaf_nodes
        self.min_samples_leaf = min_samples_leaf
        self.l2_regularization = l2_regularization
        self.monotonic_cst = monotonic_cst
        self.cv = cv
        self.max_false_alarm = max_false_alarm
        self.tune_thresholds = tune_thresholds
        self.random_state = random_state

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.allow_nan = True
        return tags

    def _boosted(self, cst) -> HistGradientBoostingClassifier:
        return HistGradientBoostingClassifier(
            learning_rate=self.learning_rate, max_iter=self.max_iter, max_leaf_nodes=self.max_leaf_nodes,
            min_samples_leaf=self.min_samples_leaf, l2_regularization=self.l2_regularization,
            # No class weights: scikit-learn ≥ 1.8 then bins with weighted percentiles, ~40× slower
            # (28 s vs 0.7 s for 3000 × 316 rows); the Platt maps absorb each edge's base rate.
            monotonic_cst=cst, early_stopping=False, random_state=self.random_state,
        )

    def _constraints(self, n_features: int):
        if self.monotonic_cst is None:
            return None
        cst = np.asarray(self.monotonic_cst)
        if cst.shape != (n_features,) or not np.isin(cst, (-1, 0, 1)).all():
            raise ValueError(f"monotonic_cst: need one of -1, 0, +1 per feature ({n_features}), got shape "
                             f"{cst.shape} with values {np.unique(cst).tolist()[:5]}")
        return None if not cst.any() else cst.astype(int)

    def fit(self, X, y, groups=None, healthy=None) -> OrdinalSeverityClassifier:
        """Fit one constrained boosted model and one Platt map per class edge.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features); NaN allowed
        y : array-like of shape (n_samples,), ordered class labels
        groups : array-like of shape (n_samples,), optional
            Plant identifiers; calibration folds never split a plant.
        healthy : array-like of bool, shape (n_samples,), optional
            Rows on which ``max_false_alarm`` is bounded (``MisalignmentModel`` passes the
            perfectly aligned machines, Δ = 0); default: the rows of the lowest class.
        """

        self._validate_params()
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan")
        check_classification_targets(y)
        self.classes_, y_idx = np.unique(y, return_inverse=True)
        if len(self.classes_) < 2:
            raise ValueError(f"y: need at least two classes to fit a classifier, got only one class "
                             f"({self.classes_.tolist()})")
        if groups is not None:
            groups = np.asarray(groups)
            if groups.shape[0] != X.shape[0]:
                raise ValueError(f"groups: length {groups.shape[0]} does not match X ({X.shape[0]} rows)")
        cst = self._constraints(X.shape[1])
        healthy = (y_idx == 0) if healthy is None else np.asarray(healthy, dtype=bool)
        if healthy.shape != (X.shape[0],):
            raise ValueError(f"healthy: need one flag per row ({X.shape[0]}), got shape {healthy.shape}")
        self.sparse_columns_ = _sparse_columns(X)
        X = _blank(X, self.sparse_columns_)
        self.models_ = []
        platt = np.tile([1.0, 0.0], (len(self.classes_) - 1, 1))
        thresholds = np.full(len(self.classes_) - 1, 0.5)
        oof = np.full((X.shape[0], len(self.classes_) - 1), np.nan)
        for k in range(1, len(self.classes_)):
            target = (y_idx >= k).astype(int)
            self.models_.append(self._binary(X, target, cst))
            scores = self._oof_scores(X, target, groups, cst)
            if scores is not None:
                platt[k - 1] = self._platt(scores, target)
                oof[:, k - 1] = _sigmoid(platt[k - 1, 0] * scores + platt[k - 1, 1])
                if k == 1 and self.max_false_alarm is not None:
                    if healthy.any():
                        thresholds[0] = max(0.5, float(np.quantile(oof[healthy, 0], 1.0 - self.max_false_alarm)))
        self.platt_ = platt
        if self.tune_thresholds and np.isfinite(oof).all():
            thresholds = _macro_f1_thresholds(np.minimum.accumulate(oof, axis=1), y_idx, thresholds)
        self.thresholds_ = thresholds
        self.n_iter_ = int(max(getattr(m, "n_iter_", 0) for m in self.models_))
        return self

    def _binary(self, X, target, cst) -> HistGradientBoostingClassifier:
        # Both sides of every edge have rows: the classes are those present in y.
        return self._boosted(cst).fit(X, target)

    def _oof_scores(self, X, target, groups, cst) -> np.ndarray | None:
        counts = np.bincount(target, minlength=2)
        n_splits = min(int(self.cv), int(counts.min()))
        if groups is not None:
            n_splits = min(n_splits, len(np.unique(groups)))
        if n_splits < 2:
            return None
        if groups is not None:
            splits = GroupKFold(n_splits=n_splits, shuffle=True, random_state=self.random_state).split(X, target, groups)
        else:
            splits = StratifiedKFold(n_splits=n_splits, shuffle=True, random_state=self.random_state).split(X, target)
        scores = np.zeros(X.shape[0])
        for tr, te in splits:
            if target[tr].min() == target[tr].max():   # a fold without one side: a sure score
                scores[te] = 30.0 if target[tr][0] else -30.0
                continue
            scores[te] = _decision(self._binary(X[tr], target[tr], cst), X[te])
        return scores

    @staticmethod
    def _platt(scores: np.ndarray, target: np.ndarray) -> tuple[float, float]:
        if target.min() == target.max() or not np.isfinite(scores).all():
            return 1.0, 0.0
        lr = LogisticRegression(C=1e4).fit(scores[:, None], target)
        a, b = float(lr.coef_[0, 0]), float(lr.intercept_[0])
        # a ≤ 0 would reverse the trees' order (and the monotonicity): keep the trees' own scale.
        return (a, b) if a > 0 and np.isfinite(a) and np.isfinite(b) else (1.0, 0.0)

    def edge_scores(self, X) -> np.ndarray:
        """The trees' decision value for each edge, shape (n_samples, K − 1).

        (Not scikit-learn's ``decision_function``, whose columns are per class.)
        """

        check_is_fitted(self, "models_")
        X = _blank(validate_data(self, X, reset=False, ensure_all_finite="allow-nan"), self.sparse_columns_)
        return np.column_stack([_decision(m, X) for m in self.models_])

    def proba_from_scores(self, scores: np.ndarray) -> np.ndarray:
        """Band probabilities from decision values (the compiled predictor's path too)."""
        scores = np.asarray(scores, dtype=float)
        cum = _sigmoid(self.platt_[:, 0] * scores + self.platt_[:, 1])
        return cumulative_to_proba(cum)

    def predict_proba(self, X) -> np.ndarray:
        """Calibrated class probabilities, shape (n_samples, n_classes), in class order."""
        return self.proba_from_scores(self.edge_scores(X))

    def class_index(self, proba: np.ndarray) -> np.ndarray:
        """The predicted class of each row of class probabilities: the largest k whose edges
        1..k all reach their threshold (the median class when every threshold is 0.5)."""
        proba = np.atleast_2d(np.asarray(proba, dtype=float))
        cum = np.cumsum(proba[:, ::-1], axis=1)[:, ::-1][:, 1:]        # P(class ≥ k), k = 1..K−1
        thresholds = getattr(self, "thresholds_", np.full(cum.shape[1], 0.5))
        passed = cum >= thresholds[None, :] - 1e-12
        return np.cumprod(passed, axis=1).sum(axis=1).astype(int)

    def predict(self, X) -> np.ndarray:
        """The predicted class of each row (see :meth:`class_index`; monotone in the constrained
        features)."""
        index = self.class_index(self.predict_proba(X))
        return self.classes_[index]


#: Candidate thresholds of the edges tuned for macro-F1 (``tune_thresholds``).
THRESHOLD_GRID = np.round(np.arange(0.20, 0.801, 0.025), 3)


def _macro_f1_thresholds(cum: np.ndarray, y_idx: np.ndarray, start: np.ndarray) -> np.ndarray:
    """Edge thresholds that maximise the out-of-fold macro-F1 (coordinate ascent on a grid).

    ``cum`` holds the out-of-fold calibrated ``P(class ≥ k)`` (non-increasing in k), ``start``
    the thresholds to start from; the first edge never goes below ``start[0]`` (the
    ``max_false_alarm`` bound), the others move on :data:`THRESHOLD_GRID`. Ties keep the
    earlier (lower) candidate, and the start wins ties, so the result is deterministic.
    """
    from sklearn.metrics import f1_score

    labels = np.arange(cum.shape[1] + 1)

    def score(t: np.ndarray) -> float:
        pred = np.cumprod(cum >= t[None, :] - 1e-12, axis=1).sum(axis=1)
        return float(f1_score(y_idx, pred, labels=labels, average="macro", zero_division=0.0))

    first = THRESHOLD_GRID[THRESHOLD_GRID >= start[0]]
    best, _ = coordinate_ascent(score, start, lambda k, _th: first if k == 0 else THRESHOLD_GRID,
                                n_passes=3, tol=1e-9)        # a few sweeps; usually converged after two
    return best


def _decision(model, X) -> np.ndarray:
    return np.asarray(model.decision_function(X), dtype=float).ravel()
