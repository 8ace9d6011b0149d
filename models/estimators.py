"""scikit-learn estimators for misalignment diagnosis.

Three components, each a scikit-learn estimator that passes
``sklearn.utils.estimator_checks`` (see ``tests/test_models_estimators.py``):

- :class:`SeverityClassifier` — gradient-boosted trees (native NaN handling) whose
  probabilities are calibrated out of fold (``CalibratedClassifierCV``) with folds
  that keep every plant on one side (``StratifiedGroupKFold``) when ``groups`` are given.
- :class:`ConformalIntervalRegressor` — Δ point estimate plus a normalised split-conformal
  interval (Lei et al. 2018): centre ± q̂·σ(x), σ a learned residual scale, q̂ calibrated
  on plants the interval models never saw.
- :class:`KNNDistanceOOD` — out-of-distribution score: distance to the k-th nearest
  training point in median-imputed, standardised feature space, thresholded at a
  quantile of the training points' leave-one-out distances.

:class:`MisalignmentModel` bundles the three with the severity bands and the feature
names; it is the one object the registry stores and :func:`models.pipeline.diagnose_recording` uses.
"""
from __future__ import annotations

import math
import re
import warnings
from collections.abc import Sequence
from functools import lru_cache
from numbers import Integral, Real

import numpy as np
from sklearn.base import (
    BaseEstimator,
    ClassifierMixin,
    OutlierMixin,
    RegressorMixin,
    clone,
)
from sklearn.calibration import CalibratedClassifierCV
from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor
from sklearn.impute import SimpleImputer
from sklearn.model_selection import (
    GroupKFold,
    GroupShuffleSplit,
    KFold,
    ShuffleSplit,
    StratifiedGroupKFold,
    StratifiedKFold,
    cross_val_predict,
)
from sklearn.neighbors import NearestNeighbors
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from rotordiag.core.bands import DEFAULT_EDGES, DEFAULT_NAMES, SeverityBands
from rotordiag.core.journal import ATTITUDE_MIN_ECC, attitude_angle_deg, attitude_offset_deg

from ._columns import _blank, _sparse_columns
from ._patterns import name_mask, pattern_value, require_matches
from ._sklearn_private import Interval, StrOptions
from .ordinal import OrdinalSeverityClassifier

_CALIBRATION_METHODS = ("temperature", "sigmoid", "isotonic", "none")


#: envelope features read with a relative tolerance on their training range: a running speed is known to about
#: ±1 % — a stated speed is locked to the record's own lines within 1 % (``features._speed_lock``), an estimate
#: scatters — so a machine at the edge of the training speeds (3600 r/min, the top of the specs' range) read at
#: 3606 r/min is not outside them (docs/robustness.md, seeds 815–817: 6–16 of 240 rated-machine presets were)
ENVELOPE_REL_TOLERANCE: dict[str, float] = {"speed_rpm": 0.01}

#: training recordings (OOD reference rows) a recording is compared with when a check asks what machines like it
#: do (:meth:`MisalignmentModel.attitude_reference_deg`; ``models.checks.backward_whirl`` asks as many), and how
#: many of them must define a bearing's attitude for it to be theirs (else the training's overall median)
NEAREST_TRAINING = 20
ATTITUDE_MIN_NEIGHBOURS = 5


def blank_clearance(X: np.ndarray, columns: np.ndarray, share: float, seed: int) -> np.ndarray:
    """Copy of X with the clearance ``columns`` set to NaN in a seeded ``share`` of the rows."""
    X = np.array(X, dtype=float, copy=True)
    if share <= 0 or not np.any(columns):
        return X
    rows = np.random.default_rng(seed).random(X.shape[0]) < share
    X[np.ix_(np.asarray(rows), np.asarray(columns))] = np.nan
    return X


def _nan_tags(tags):
    tags.input_tags.allow_nan = True
    return tags


class SeverityClassifier(ClassifierMixin, BaseEstimator):
    """Gradient-boosted severity classifier with out-of-fold calibrated probabilities.

    Parameters
    ----------
    learning_rate, max_iter, max_leaf_nodes, min_samples_leaf, l2_regularization :
        Passed to :class:`~sklearn.ensemble.HistGradientBoostingClassifier`.
    class_weight : {"balanced", None}, default="balanced"
        Class weighting of the boosted trees (the bands are rarely balanced).
    calibration : {"temperature", "sigmoid", "isotonic", "none"}, default="temperature"
        Calibration map fitted on out-of-fold scores (``CalibratedClassifierCV`` with
        ``ensemble=False``: one model trained on all rows, the map on cross-validated
        predictions). Temperature scaling is one parameter for all classes, which suits
        a few hundred to a few thousand rows.
    cv : int, default=5
        Number of calibration folds (reduced to the number of groups, or of members of
        the smallest class, when those are fewer; calibration is skipped below 2).
    random_state : int, default=0
        Seed of the fold shuffling and the trees.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
    n_features_in_ : int
    model_ : fitted classifier (calibrated or plain boosted trees)
    calibrated_ : bool
        Whether ``model_`` carries a calibration map.
    calibration_note_ : str
        Only when temperature scaling failed to optimise (scikit-learn raises on NaN): why the
        trees' own probabilities are used.
    n_iter_ : int
        Boosting iterations of the trees.
    """

    _parameter_constraints = {
        "learning_rate": [Interval(Real, 0, None, closed="neither")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
        "max_leaf_nodes": [Interval(Integral, 2, None, closed="left")],
        "min_samples_leaf": [Interval(Integral, 1, None, closed="left")],
        "l2_regularization": [Interval(Real, 0, None, closed="left")],
        "class_weight": [StrOptions({"balanced"}), dict, None],
        "calibration": [StrOptions(set(_CALIBRATION_METHODS))],
        "cv": [Interval(Integral, 2, None, closed="left")],
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
        class_weight: str | None = "balanced",
        calibration: str = "temperature",
        cv: int = 5,
        random_state: int = 0,
    ) -> None:
        self.learning_rate = learning_rate
        self.max_iter = max_iter
        self.max_leaf_nodes = max_leaf_nodes
        self.min_samples_leaf = min_samples_leaf
        self.l2_regularization = l2_regularization
        self.class_weight = class_weight
        self.calibration = calibration
        self.cv = cv
        self.random_state = random_state

    def __sklearn_tags__(self):
        return _nan_tags(super().__sklearn_tags__())

    def _boosted(self) -> HistGradientBoostingClassifier:
        return HistGradientBoostingClassifier(
            learning_rate=self.learning_rate,
            max_iter=self.max_iter,
            max_leaf_nodes=self.max_leaf_nodes,
            min_samples_leaf=self.min_samples_leaf,
            l2_regularization=self.l2_regularization,
            class_weight=self.class_weight,
            early_stopping=False,
            random_state=self.random_state,
        )

    def fit(self, X, y, groups=None) -> SeverityClassifier:
        """Fit the trees and the calibration map.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features); NaN allowed
        y : array-like of shape (n_samples,) class labels
        groups : array-like of shape (n_samples,), optional
            Plant identifiers; calibration folds never split a plant.
        """
        self._validate_params()
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan")
        check_classification_targets(y)
        self.sparse_columns_ = _sparse_columns(X)
        X = _blank(X, self.sparse_columns_)
        self.classes_, counts = np.unique(y, return_counts=True)
        if len(self.classes_) < 2:
            raise ValueError(
                f"y: need at least two classes to fit a classifier, got only one class "
                f"({self.classes_.tolist()})"
            )
        n_splits = min(int(self.cv), int(counts.min()))
        if groups is not None:
            groups = np.asarray(groups)
            if groups.shape[0] != X.shape[0]:
                raise ValueError(f"groups: length {groups.shape[0]} does not match X ({X.shape[0]} rows)")
            n_splits = min(n_splits, len(np.unique(groups)))
        self.calibrated_ = self.calibration != "none" and n_splits >= 2
        if not self.calibrated_:
            self.model_ = self._boosted().fit(X, y)
            self.n_iter_ = int(self.model_.n_iter_)
            return self
        if groups is not None:
            splitter = StratifiedGroupKFold(n_splits=n_splits, shuffle=True, random_state=self.random_state)
            splits = list(splitter.split(X, y, groups))
        else:
            splitter = StratifiedKFold(n_splits=n_splits, shuffle=True, random_state=self.random_state)
            splits = list(splitter.split(X, y))
        try:
            self.model_ = CalibratedClassifierCV(
                self._boosted(), method=self.calibration, cv=splits, ensemble=False
            ).fit(X, y)
        except RuntimeError as exc:
            # scikit-learn's temperature scaling raises when its 1-D optimisation meets NaN
            # (out-of-fold scores that separate the classes perfectly); the trees' own
            # probabilities are then the honest answer, and the fit says so.
            if self.calibration != "temperature" or "Temperature scaling" not in str(exc):
                raise
            self.calibrated_ = False
            self.calibration_note_ = f"calibration skipped: {exc}"
            self.model_ = self._boosted().fit(X, y)
            self.n_iter_ = int(self.model_.n_iter_)
            return self
        self.n_iter_ = int(self.model_.calibrated_classifiers_[0].estimator.n_iter_)
        return self

    def predict_proba(self, X) -> np.ndarray:
        """Calibrated class probabilities, shape (n_samples, n_classes), columns in ``classes_`` order."""
        check_is_fitted(self, "model_")
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan")
        return self.model_.predict_proba(_blank(X, self.sparse_columns_))

    def predict(self, X) -> np.ndarray:
        """Most probable class of each row."""
        proba = self.predict_proba(X)
        return self.classes_[np.argmax(proba, axis=1)]


class ConformalIntervalRegressor(RegressorMixin, BaseEstimator):
    """Δ regressor with a normalised split-conformal interval.

    The point estimate is a squared-error boosted model trained on all rows. The
    interval is ``c(x) ± q̂ · σ(x)``: a centre model ``c`` trained on a "proper" part of
    the rows, a scale model ``σ`` trained on the proper part's out-of-fold absolute
    residuals of ``c`` (floored at their 10th percentile), and q̂ the conformal quantile
    of ``|y − c(x)| / σ(x)`` on the held-out calibration part (Lei et al. 2018). With
    exchangeable rows (plants, when ``groups`` are given) it covers the truth with
    probability ≥ 1 − α whatever ``c`` and ``σ`` are; σ makes it narrow where the
    residuals are small. The interval is then widened, never narrowed, to contain the
    point estimate and clipped below at ``lower_bound`` (Δ ≥ 0), neither of which can
    lower the coverage.

    (Not conformalised quantile regression: boosted quantile models at α/2 cannot leave a
    target with many exact ties at its lower end — Δ = 0 for every aligned machine: every
    gradient is equal, no split has any gain, and the lower quantile stays 0 for every row,
    giving uninformative intervals.)

    Parameters
    ----------
    alpha : float, default=0.1
        Miscoverage level (0.1 → 90 % interval).
    calibration_fraction : float, default=0.25
        Share of rows (of groups, when given) held out to calibrate the interval.
    lower_bound : float or None, default=None
        Physical lower bound of the target, applied to point and interval
        (:class:`MisalignmentModel` uses 0: Δ ≥ 0).
    learning_rate, max_iter, max_leaf_nodes, min_samples_leaf, l2_regularization :
        Passed to :class:`~sklearn.ensemble.HistGradientBoostingRegressor`.
    random_state : int, default=0

    Attributes
    ----------
    point_model_, center_model_ : fitted regressors
    scale_model_ : fitted regressor or None (None: constant scale, when too few rows)
    scale_floor_ : float
    conformity_quantile_ : float
        q̂ (``inf`` when the calibration part is too small for the requested α).
    n_calibration_ : int
    n_iter_ : int
        Boosting iterations of the point model.
    """

    _parameter_constraints = {
        "alpha": [Interval(Real, 0, 1, closed="neither")],
        "calibration_fraction": [Interval(Real, 0, 1, closed="neither")],
        "lower_bound": [Real, None],
        "learning_rate": [Interval(Real, 0, None, closed="neither")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
        "max_leaf_nodes": [Interval(Integral, 2, None, closed="left")],
        "min_samples_leaf": [Interval(Integral, 1, None, closed="left")],
        "l2_regularization": [Interval(Real, 0, None, closed="left")],
        "monotonic_cst": ["array-like", None],
        "random_state": ["random_state"],
    }

    def __init__(
        self,
        *,
        alpha: float = 0.1,
        calibration_fraction: float = 0.25,
        lower_bound: float | None = None,
        learning_rate: float = 0.1,
        max_iter: int = 150,
        max_leaf_nodes: int = 15,
        min_samples_leaf: int = 10,
        l2_regularization: float = 1.0,
        monotonic_cst=None,
        random_state: int = 0,
    ) -> None:
        self.alpha = alpha
        self.calibration_fraction = calibration_fraction
        self.lower_bound = lower_bound
        self.learning_rate = learning_rate
        self.max_iter = max_iter
        self.max_leaf_nodes = max_leaf_nodes
        self.min_samples_leaf = min_samples_leaf
        self.l2_regularization = l2_regularization
        self.monotonic_cst = monotonic_cst
        self.random_state = random_state

    def __sklearn_tags__(self):
        return _nan_tags(super().__sklearn_tags__())

    def _boosted(self, **loss) -> HistGradientBoostingRegressor:
        return HistGradientBoostingRegressor(
            learning_rate=self.learning_rate,
            max_iter=self.max_iter,
            max_leaf_nodes=self.max_leaf_nodes,
            min_samples_leaf=self.min_samples_leaf,
            l2_regularization=self.l2_regularization,
            early_stopping=False,
            random_state=self.random_state,
            **loss,
        )

    def fit(self, X, y, groups=None) -> ConformalIntervalRegressor:
        """Fit point, centre and scale models and calibrate the interval.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features); NaN allowed
        y : array-like of shape (n_samples,)
        groups : array-like of shape (n_samples,), optional
            Plant identifiers; the calibration part holds whole plants.
        """
        self._validate_params()
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan", y_numeric=True)
        y = y.astype(float)
        self.sparse_columns_ = _sparse_columns(X)
        X = _blank(X, self.sparse_columns_)
        n = X.shape[0]
        if n < 2:
            raise ValueError(f"X: need at least 2 samples to fit an interval regressor, got n_samples = {n}")
        if groups is not None:
            groups = np.asarray(groups)
            if groups.shape[0] != n:
                raise ValueError(f"groups: length {groups.shape[0]} does not match X ({n} rows)")
        if groups is not None and len(np.unique(groups)) >= 2:
            split = GroupShuffleSplit(
                n_splits=1, test_size=self.calibration_fraction, random_state=self.random_state
            )
            proper, calib = next(split.split(X, y, groups))
        else:
            split = ShuffleSplit(n_splits=1, test_size=self.calibration_fraction, random_state=self.random_state)
            proper, calib = next(split.split(X, y))
        a = float(self.alpha)
        cst = None
        if self.monotonic_cst is not None:
            cst = np.asarray(self.monotonic_cst)
            if cst.shape != (X.shape[1],) or not np.isin(cst, (-1, 0, 1)).all():
                raise ValueError(f"monotonic_cst: need one of -1, 0, +1 per feature ({X.shape[1]}), got shape "
                                 f"{cst.shape}")
            cst = cst.astype(int) if cst.any() else None
        self.point_model_ = self._boosted(loss="squared_error", monotonic_cst=cst).fit(X, y)
        Xp, yp = X[proper], y[proper]
        self.center_model_ = self._boosted(loss="squared_error", monotonic_cst=cst).fit(Xp, yp)
        self.scale_model_ = None
        self.scale_floor_ = 1.0
        if len(proper) >= 6:
            gp = groups[proper] if groups is not None else None
            if gp is not None and len(np.unique(gp)) >= 3:
                folds = list(GroupKFold(n_splits=3).split(Xp, yp, gp))
            else:
                folds = list(KFold(n_splits=3, shuffle=True, random_state=self.random_state).split(Xp))
            resid = np.abs(yp - cross_val_predict(self._boosted(loss="squared_error", monotonic_cst=cst), Xp, yp,
                                                  cv=folds))
            floor = float(np.quantile(resid, 0.1))
            if floor > 0 or resid.max() > 0:
                self.scale_floor_ = floor if floor > 0 else float(resid[resid > 0].min())
                self.scale_model_ = self._boosted(loss="squared_error").fit(Xp, resid)
        scores = np.abs(y[calib] - self.center_model_.predict(X[calib])) / self._scale(X[calib])
        m = scores.shape[0]
        rank = math.ceil((m + 1) * (1 - a))
        self.conformity_quantile_ = float(np.sort(scores)[rank - 1]) if rank <= m else math.inf
        self.n_calibration_ = int(m)
        self.n_iter_ = int(self.point_model_.n_iter_)
        return self

    def _scale(self, X: np.ndarray) -> np.ndarray:
        if self.scale_model_ is None:
            return np.full(X.shape[0], self.scale_floor_)
        return np.maximum(self.scale_model_.predict(X), self.scale_floor_)

    def _clip(self, v: np.ndarray) -> np.ndarray:
        return v if self.lower_bound is None else np.maximum(v, self.lower_bound)

    def predict(self, X) -> np.ndarray:
        """Point estimate, shape (n_samples,)."""
        check_is_fitted(self, "point_model_")
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan")
        return self._clip(self.point_model_.predict(_blank(X, self.sparse_columns_)))

    def predict_interval(self, X) -> np.ndarray:
        """Conformal interval, shape (n_samples, 2): columns lower, upper."""
        check_is_fitted(self, "point_model_")
        X = _blank(validate_data(self, X, reset=False, ensure_all_finite="allow-nan"), self.sparse_columns_)
        point = self._clip(self.point_model_.predict(X))
        centre = self.center_model_.predict(X)
        with np.errstate(invalid="ignore"):   # q̂ = inf: an honest unbounded interval
            half = self.conformity_quantile_ * self._scale(X)
        lo = np.minimum(centre - half, point)
        hi = np.maximum(centre + half, point)
        return np.column_stack([self._clip(lo), self._clip(hi)])


class KNNDistanceOOD(OutlierMixin, BaseEstimator):
    """Out-of-distribution score: k-th-neighbour distance in standardised feature space.

    Features are median-imputed (a feature that is always missing becomes 0) and
    standardised with the training statistics. A row's distance is the Euclidean
    distance to its ``n_neighbors``-th nearest reference row; the threshold is the
    ``threshold_quantile`` of the same distance over training rows of groups (plants) kept
    out of the reference (see :meth:`fit`). So about ``1 − threshold_quantile`` of
    recordings of *new* plants like the training data are flagged, and rows far from all
    of it always are.

    Parameters
    ----------
    n_neighbors : int, default=5
    threshold_quantile : float, default=0.99
    max_reference : int, default=2000
        At most this many training rows (whole groups, a seeded random choice) are kept as
        the reference set, which bounds model size and query time; the other rows
        calibrate the threshold.
    random_state : int, default=0

    Attributes
    ----------
    preprocess_ : Pipeline (SimpleImputer → StandardScaler)
    reference_ : ndarray of shape (n_reference, n_features), float32
    reference_rows_ : ndarray of int of shape (n_reference,)
        The fitted X's rows that make up the reference, in its order (what else a model keeps per reference row:
        ``MisalignmentModel.reference_attitude_offset_deg_``).
    threshold_ : float
        Distance above which a row is out of distribution.
    offset_ : float
        ``-threshold_``; ``decision_function = score_samples - offset_`` (scikit-learn's
        outlier convention: negative means outlier).
    """

    _parameter_constraints = {
        "n_neighbors": [Interval(Integral, 1, None, closed="left")],
        "threshold_quantile": [Interval(Real, 0, 1, closed="right")],
        "max_reference": [Interval(Integral, 2, None, closed="left")],
        "random_state": ["random_state"],
    }

    def __init__(
        self,
        *,
        n_neighbors: int = 5,
        threshold_quantile: float = 0.99,
        max_reference: int = 2000,
        random_state: int = 0,
    ) -> None:
        self.n_neighbors = n_neighbors
        self.threshold_quantile = threshold_quantile
        self.max_reference = max_reference
        self.random_state = random_state

    def __sklearn_tags__(self):
        return _nan_tags(super().__sklearn_tags__())

    def fit(self, X, y=None, groups=None) -> KNNDistanceOOD:
        """Store the standardised reference set and the distance threshold.

        The threshold is calibrated on rows of groups (plants) that are **not** in the
        reference set: whole groups, in a seeded random order, fill the reference up to
        ``max_reference`` rows, and the threshold is the ``threshold_quantile`` of the other
        groups' distances — what a new plant of the same family scores. When every row fits
        in the reference, the distances come from a 5-fold split by group instead (each
        fold measured against the other folds). Rows of one group (e.g. augmented copies
        of one plant's recording) never measure each other, so near-duplicates cannot
        shrink the threshold.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features); NaN allowed
        y : ignored
        groups : array-like of shape (n_samples,), optional
            Plant identifiers (default: every row its own group).
        """
        self._validate_params()
        X = validate_data(self, X, ensure_all_finite="allow-nan")
        n = X.shape[0]
        if n < 2:
            raise ValueError(f"X: need at least 2 samples to fit an OOD scorer, got n_samples = {n}")
        groups = np.arange(n) if groups is None else np.asarray(groups)
        if groups.shape[0] != n:
            raise ValueError(f"groups: length {groups.shape[0]} does not match X ({n} rows)")
        self.preprocess_ = Pipeline(
            [
                ("impute", SimpleImputer(strategy="median", keep_empty_features=True)),
                ("scale", StandardScaler()),
            ]
        ).fit(X)
        Z = self.preprocess_.transform(X).astype(np.float32)
        rng = np.random.default_rng(self.random_state)
        uniq, inverse = np.unique(groups, return_inverse=True)
        order = rng.permutation(len(uniq))
        sizes = np.bincount(inverse)[order]
        n_ref_groups = max(1, int(np.searchsorted(np.cumsum(sizes), self.max_reference, side="right")))
        in_ref = np.zeros(len(uniq), bool)
        in_ref[order[:n_ref_groups]] = True
        ref_rows = in_ref[inverse]
        if (~ref_rows).sum() >= 2 and ref_rows.sum() >= 2:
            self.reference_ = Z[ref_rows]
            self.reference_rows_ = np.flatnonzero(ref_rows)
            self.k_ = int(min(self.n_neighbors, self.reference_.shape[0]))
            calib = self._kth_distance(Z[~ref_rows])
            self.calibration_ = "held-out groups"
        else:
            self.reference_ = Z
            self.reference_rows_ = np.arange(n)
            self.k_ = int(min(self.n_neighbors, n - 1))
            fold_of_group = rng.permutation(len(uniq)) % min(5, len(uniq))
            fold = fold_of_group[inverse]
            calib = np.empty(n)
            for f in np.unique(fold):
                rest = Z[fold != f]
                k = int(min(self.k_, rest.shape[0]))
                d, _ = NearestNeighbors(n_neighbors=k).fit(rest).kneighbors(Z[fold == f])
                calib[fold == f] = d[:, k - 1]
            self.calibration_ = "group k-fold"
        self.n_calibration_ = int(calib.size)
        self.threshold_ = float(np.quantile(calib, self.threshold_quantile))
        self.offset_ = -self.threshold_
        return self

    def _kth_distance(self, Z: np.ndarray) -> np.ndarray:
        d, _ = NearestNeighbors(n_neighbors=self.k_).fit(self.reference_).kneighbors(Z)
        return d[:, self.k_ - 1].astype(float)

    def distance(self, X) -> np.ndarray:
        """Distance to the k-th nearest reference row, shape (n_samples,)."""
        check_is_fitted(self, "reference_")
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan")
        # The neighbour index is rebuilt per call (cheap for ≤ a few thousand rows), so the
        # stored model holds only plain arrays.
        return self._kth_distance(self.preprocess_.transform(X).astype(np.float32))

    def score_samples(self, X) -> np.ndarray:
        """Negative distance (higher = more normal)."""
        return -self.distance(X)

    def decision_function(self, X) -> np.ndarray:
        """``score_samples - offset_``; negative values are out of distribution."""
        return self.score_samples(X) - self.offset_

    def predict(self, X) -> np.ndarray:
        """+1 for in-distribution rows, −1 for out-of-distribution rows."""
        return np.where(self.decision_function(X) < 0, -1, 1)

    def ood_ratio(self, X) -> np.ndarray:
        """Distance divided by the threshold: > 1 means out of distribution."""
        return self.distance(X) / max(self.threshold_, np.finfo(float).tiny)

    def nearest_reference(self, x, n_neighbors: int, ignore: int | None = None) -> np.ndarray:
        """Indices of the ``n_neighbors`` reference rows nearest to the row ``x`` (nearest first).

        The distance is taken over the columns ``x`` has (finite), column ``ignore`` left out (so a row's own value
        of that column does not choose its neighbours), in the standardised space of :meth:`distance`.
        """
        check_is_fitted(self, "reference_")
        x = np.asarray(x, dtype=float).reshape(-1)
        if x.shape[0] != self.reference_.shape[1] or (ignore is not None and not 0 <= ignore < x.shape[0]):
            raise ValueError(f"x: {x.shape[0]} columns (ignore={ignore}); the reference has "
                             f"{self.reference_.shape[1]} columns")
        scale = self.preprocess_.named_steps["scale"]
        z = (x - scale.mean_) / scale.scale_
        use = np.isfinite(z)
        if ignore is not None:
            use[ignore] = False
        diff = self.reference_[:, use].astype(float) - z[use]
        d = np.einsum("ij,ij->i", diff, diff)
        return np.argsort(d, kind="stable")[: int(min(n_neighbors, d.size))]

    def neighbour_values(self, x, column: int, n_neighbors: int) -> np.ndarray:
        """Column ``column`` (in X's units) of the :meth:`nearest_reference` rows of ``x``, the column itself left
        out of the distance: what training rows *like this one* show there. Reference rows whose value was missing
        in training carry the imputed training median."""
        nearest = self.nearest_reference(x, n_neighbors, ignore=column)
        scale = self.preprocess_.named_steps["scale"]
        return self.reference_[nearest, column].astype(float) * scale.scale_[column] + scale.mean_[column]


class FeatureEnvelope(BaseEstimator):
    """Per-feature training range with a margin calibrated on held-out plants.

    Each column's training range ``[lo, hi]`` (min and max over the training rows); a row
    is outside when a value lies below ``lo`` (only where ``check_low`` says so) or above
    ``hi`` by more than ``margin_`` × the column's spread (its 5–95 % range). The margin is
    the ``quantile`` of the largest such excess of rows of plants held out of the range
    (a group k-fold: rows of one plant, e.g. augmented copies, never bound each other), so
    about ``1 − quantile`` of recordings of new plants of the family are outside. Unlike a
    nearest-neighbour distance over many columns, one extreme column is enough, and the
    excess says which column and by how much.

    Parameters
    ----------
    quantile : float, default=0.99
    n_splits : int, default=5
        Group folds for the margin.
    random_state : int, default=0

    Attributes
    ----------
    lo_, hi_ : ndarray of shape (n_features,)
        Training min / max (−inf / +inf for a column never measured).
    spread_ : ndarray of shape (n_features,)
    check_low_ : ndarray of bool
    margin_ : float
        In spreads; a row is outside when its largest excess is above it.
    """

    _parameter_constraints = {
        "quantile": [Interval(Real, 0, 1, closed="right")],
        "n_splits": [Interval(Integral, 2, None, closed="left")],
        "random_state": ["random_state"],
    }

    def __init__(self, *, quantile: float = 0.99, n_splits: int = 5, random_state: int = 0) -> None:
        self.quantile = quantile
        self.n_splits = n_splits
        self.random_state = random_state

    def __sklearn_tags__(self):
        return _nan_tags(super().__sklearn_tags__())

    @staticmethod
    def _range(Z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        seen = np.isfinite(Z).any(axis=0)
        Zs = np.where(seen, Z, 0.0)
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            lo = np.where(seen, np.nanmin(Zs, axis=0), -np.inf)
            hi = np.where(seen, np.nanmax(Zs, axis=0), np.inf)
            q = np.nanquantile(Zs, [0.05, 0.95], axis=0)
        spread = np.where(seen, q[1] - q[0], 1.0)
        tiny = 1e-9 * np.maximum(np.abs(lo[np.isfinite(lo)]).max(initial=1.0), 1.0)
        return lo, hi, np.maximum(spread, tiny)

    def _excess(self, Z: np.ndarray, lo: np.ndarray, hi: np.ndarray, spread: np.ndarray,
                check_low: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore"):
            below = np.where(check_low, lo - Z, -np.inf)
            v = np.maximum(below, Z - hi) / spread
        return np.where(np.isfinite(v), np.maximum(v, 0.0), 0.0)

    def fit(self, X, y=None, groups=None, check_low=None) -> FeatureEnvelope:
        """Training range, spread and the margin (see the class docstring).

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features); NaN allowed (not measured)
        y : ignored
        groups : array-like of shape (n_samples,), optional
            Plant identifiers (default: every row its own group).
        check_low : array-like of bool of shape (n_features,), optional
            Columns whose low side is checked too (default: all); e.g. a noise share that is
            lower than in training is no reason to doubt a verdict.
        """
        self._validate_params()
        Z = validate_data(self, X, ensure_all_finite="allow-nan").astype(float)
        n, p = Z.shape
        if n < 2 * self.n_splits:
            raise ValueError(f"X: need at least {2 * self.n_splits} samples to fit an envelope, got {n}")
        groups = np.arange(n) if groups is None else np.asarray(groups)
        if groups.shape[0] != n:
            raise ValueError(f"groups: length {groups.shape[0]} does not match X ({n} rows)")
        self.check_low_ = np.ones(p, bool) if check_low is None else np.asarray(check_low, bool)
        if self.check_low_.shape != (p,):
            raise ValueError(f"check_low: expected {p} flags, got shape {self.check_low_.shape}")
        uniq, inverse = np.unique(groups, return_inverse=True)
        k = int(min(self.n_splits, len(uniq)))
        if k < 2:
            raise ValueError("groups: need at least 2 groups to calibrate the envelope on held-out plants")
        fold = (np.random.default_rng(self.random_state).permutation(len(uniq)) % k)[inverse]
        worst = np.empty(n)
        for f in range(k):
            lo, hi, spread = self._range(Z[fold != f])
            worst[fold == f] = self._excess(Z[fold == f], lo, hi, spread, self.check_low_).max(axis=1, initial=0.0)
        self.margin_ = float(np.quantile(worst, self.quantile))
        self.calibration_flag_rate_ = float(np.mean(worst > self.margin_))
        self.lo_, self.hi_, self.spread_ = self._range(Z)
        return self

    def excess(self, X) -> np.ndarray:
        """How far each value lies outside the training range, in spreads (0 inside or missing), (n, p)."""
        check_is_fitted(self, "margin_")
        Z = validate_data(self, X, reset=False, ensure_all_finite="allow-nan").astype(float)
        return self._excess(Z, self.lo_, self.hi_, self.spread_, self.check_low_)

    def outside(self, X) -> np.ndarray:
        """Which values are outside the range plus the margin, bool (n, p)."""
        return self.excess(X) > self.margin_

    def predict(self, X) -> np.ndarray:
        """+1 inside, −1 when any value is outside."""
        return np.where(self.outside(X).any(axis=1), -1, 1)


@lru_cache(maxsize=16)
def _amplitude_centre_pairs(names: tuple[str, ...], cols: bytes) -> tuple[tuple[int, int], ...]:
    """(1X per clearance, centreline eccentricity) column pairs of each bearing, both clearance columns (``cols``:
    ``clearance_columns_`` as bytes), that :meth:`MisalignmentModel.clearance_stated` reads; built once per model."""
    is_col = np.frombuffer(cols, dtype=bool)
    index = {n: j for j, n in enumerate(names)}
    pairs = []
    for name, ja in index.items():
        if not name.endswith("_1x_major_pp_per_c"):
            continue
        jc = index.get(name.replace("_1x_major_pp_per_c", "_centre_ecc_per_c"))
        if jc is not None and is_col[ja] and is_col[jc]:
            pairs.append((ja, jc))
    return tuple(pairs)


class MisalignmentModel(BaseEstimator):
    """Severity classifier + Δ interval regressor + OOD scorer, with bands and feature names.

    ``fit(X, y)`` takes the true misalignment Δ as ``y``; the severity labels are derived
    from ``band_edges``/``band_names``.

    Parameters
    ----------
    band_edges : tuple of float, default=(0.05, 0.15, 0.35)
    band_names : tuple of str, default=("aligned", "slight", "moderate", "severe")
    classifier : SeverityClassifier or None
        Template (cloned at fit); ``None`` → ``SeverityClassifier()``.
    regressor : ConformalIntervalRegressor or None
    ood : KNNDistanceOOD or None
    feature_names : sequence of str or None
        Names of the columns of X, in order; stored as ``feature_names_``.
    monotonic_increasing : sequence of str, default=()
        Glob patterns of feature names along which severity and Δ must not decrease (physics
        priors: e.g. the coupling bearings' 2X/1X). Applied as ``monotonic_cst`` = +1 to the
        classifier (an :class:`~rotordiag.models.ordinal.OrdinalSeverityClassifier`; a
        multiclass :class:`SeverityClassifier` cannot take constraints) and to the Δ
        regressor's point and centre models. Needs ``feature_names``.
    ood_features : sequence of str, default=()
        Glob patterns of the features the OOD scorer sees (default: all). A few physically
        meaningful features (amplitudes, orbit size and shaft position per clearance, 2X/1X,
        non-synchronous content) keep the distance from being diluted by hundreds of
        correlated columns. Needs ``feature_names``.
    ood_log_scales : mapping of str to float, default={}
        Pattern → scale *s*: a matching OOD feature *x* enters as ``log1p(max(x, 0) / s)``
        (first matching pattern wins), so that amplitudes and ratios are compared by their
        order of magnitude above a physical floor *s* (e.g. 1 µm, 0.01 c, a 2X/1X of 0.05)
        rather than linearly: a machine vibrating 200× less than the family is far away,
        one with a clean 0.1 µm 2X is not.
    envelope_features : sequence of str, default=()
        Glob patterns of the features whose training range is checked one by one
        (:class:`FeatureEnvelope`; default: none). Besides the feature names, two derived
        ones can be named, from ``b{n}_centre_x_per_c`` / ``b{n}_centre_y_per_c``:
        ``b{n}_attitude_deg``, the shaft centreline's attitude angle (from the load line, with
        rotation), and ``b{n}_attitude_offset_deg``, that angle minus the one a plain short
        oil-film journal bearing takes at the same eccentricity (``rotordiag.core.journal``);
        both are missing (not checked) below ``ATTITUDE_MIN_ECC`` = 0.05, where the journal
        sits at the centre and the angle is not defined. Features matching ``ood_log_scales``
        are compared as ``log10(max(x, s / 1000))``.
    envelope_upper_only : sequence of str, default=()
        Patterns of envelope features whose low side is not checked (e.g. noise shares: a
        cleaner signal than in training is no reason for doubt).
    envelope : FeatureEnvelope or None
        Template (cloned at fit); ``None`` → ``FeatureEnvelope()``.
    clearance_features : sequence of str, default=()
        Glob patterns of the features that need the bearing clearance (``*_per_c``): a
        recording *states the clearance* when any of them is finite. Needs ``feature_names``.
    clearance_dropout : float, default=0.0
        Share of the training rows (seeded by ``random_state``) whose clearance features are
        blanked before the OOD scorer, the envelope and the training medians are fitted, so
        that a recording without the clearance looks like the training data. With
        ``clearance_heads=False`` the classifier and the regressor are fitted on the same
        blanked rows (one model for both cases).
    clearance_heads : bool, default=False
        Fit a classifier and a Δ regressor for each case: ``classifier_`` / ``regressor_`` on
        every row as given (clearance stated) and ``classifier_no_clearance_`` /
        ``regressor_no_clearance_`` on every row with the clearance features blanked. Each
        recording is answered by the pair of its case (:meth:`clearance_stated`). One model
        for both cases loses accuracy on the recordings that state the clearance
        (docs/models-history.md, the clearance-dropout variants of ``bench_learning_curve``).
    random_state : int, default=0
        Seed of the ``clearance_dropout`` rows.

    Attributes
    ----------
    bands_ : SeverityBands
    classifier_, regressor_, ood_ : fitted components
    classifier_no_clearance_, regressor_no_clearance_ : fitted components or None
        The pair for recordings without the clearance (``clearance_heads``), else None.
    clearance_columns_ : ndarray of bool of shape (n_features,)
        The columns ``clearance_features`` matched.
    feature_names_ : tuple of str
    feature_median_ : ndarray of shape (n_features,)
        Training median of each feature (NaN-ignoring), the reference value used to
        explain a verdict.
    feature_nan_rate_ : ndarray of shape (n_features,)
        Share of training rows in which each feature was missing.
    attitude_offset_reference_deg_ : ndarray of shape (9,)
        Bearing ``n`` at index ``n − 1``: the training journals' median attitude angle minus a
        plain short journal bearing's (NaN where undefined); models saved before it existed
        are compared with a plain bearing's (0°).
    reference_attitude_offset_deg_ : ndarray of shape (n_reference, 9), float32, or None
        The same per OOD reference row (``ood_.reference_rows_``): :meth:`attitude_reference_deg` takes the
        recording's nearest training machines' (None: an OOD scorer without reference rows).
    classes_ : ndarray of str, the band names in order
    envelope_ : FeatureEnvelope or None
        Fitted when ``envelope_features`` is given; ``envelope_names_`` its columns.
    monotonic_cst_ : ndarray of int of shape (n_features,)
        +1 where ``monotonic_increasing`` matched, else 0.
    """

    #: models saved before these parameters existed load without them
    monotonic_increasing: Sequence[str] = ()
    ood_features: Sequence[str] = ()
    ood_log_scales: dict | None = None
    envelope_features: Sequence[str] = ()
    envelope_upper_only: Sequence[str] = ()
    envelope: FeatureEnvelope | None = None
    clearance_features: Sequence[str] = ()
    clearance_dropout: float = 0.0
    clearance_heads: bool = False
    random_state: int = 0
    classifier_no_clearance_: SeverityClassifier | OrdinalSeverityClassifier | None = None
    regressor_no_clearance_: ConformalIntervalRegressor | None = None

    def __init__(
        self,
        *,
        band_edges: Sequence[float] = DEFAULT_EDGES,
        band_names: Sequence[str] = DEFAULT_NAMES,
        classifier: SeverityClassifier | OrdinalSeverityClassifier | None = None,
        regressor: ConformalIntervalRegressor | None = None,
        ood: KNNDistanceOOD | None = None,
        feature_names: Sequence[str] | None = None,
        monotonic_increasing: Sequence[str] = (),
        ood_features: Sequence[str] = (),
        ood_log_scales: dict | None = None,
        envelope_features: Sequence[str] = (),
        envelope_upper_only: Sequence[str] = (),
        envelope: FeatureEnvelope | None = None,
        clearance_features: Sequence[str] = (),
        clearance_dropout: float = 0.0,
        clearance_heads: bool = False,
        random_state: int = 0,
    ) -> None:
        self.band_edges = band_edges
        self.band_names = band_names
        self.classifier = classifier
        self.regressor = regressor
        self.ood = ood
        self.feature_names = feature_names
        self.monotonic_increasing = monotonic_increasing
        self.ood_features = ood_features
        self.ood_log_scales = ood_log_scales
        self.envelope_features = envelope_features
        self.envelope_upper_only = envelope_upper_only
        self.envelope = envelope
        self.clearance_features = clearance_features
        self.clearance_dropout = clearance_dropout
        self.clearance_heads = clearance_heads
        self.random_state = random_state

    @property
    def ordinal_(self) -> bool:
        """Whether the classifier is ordinal (its class is the median band, not the most probable)."""
        return isinstance(getattr(self, "classifier_", None), OrdinalSeverityClassifier)

    def band_index(self, proba: np.ndarray, X=None) -> np.ndarray:
        """The predicted band of each row of band probabilities: for an ordinal classifier the
        largest band whose edges all pass their thresholds (the median band with 0.5 thresholds;
        monotone in the constrained features), else the most probable one.

        ``X`` (the rows' features) is needed when the model has a pair per clearance case
        (``clearance_heads``): each case's classifier has its own thresholds.
        """
        proba = np.atleast_2d(np.asarray(proba, dtype=float))
        if not self.ordinal_:
            return np.argmax(proba, axis=1)
        if self.classifier_no_clearance_ is None:
            return self.classifier_.class_index(proba)
        if X is None:
            raise ValueError("band_index: this model has a classifier per clearance case; pass X, the rows' "
                             "features, so that each row is read with its own case's thresholds")
        out = np.empty(proba.shape[0], dtype=int)
        for rows, stated in self.clearance_cases(X):
            out[rows] = self.heads(stated)[0].class_index(proba[rows])
        return out

    def clearance_stated(self, X) -> np.ndarray:
        """Per row, whether the clearance-stated pair answers it, bool (n,): some clearance feature is finite and,
        at every bearing whose 1X per clearance is, the shaft-centreline position per clearance too.

        The simulator's DC readings are journal positions, so wherever training stated the clearance it had the
        centreline as well, and that pair never saw it missing. A recording whose DC part is no position — a raw
        probe gap (more than 1.5 c from the probes' zero), or channels whose mean was removed — has it missing, and
        the clearance-stated pair reads it as a journal far off centre (false alarms; docs/models.md). Such a
        recording is answered by the pair trained without any clearance feature, which never relied on the
        centreline."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        cols = getattr(self, "clearance_columns_", None)
        if cols is None or not cols.any():
            return np.ones(X.shape[0], dtype=bool)
        stated = np.isfinite(X[:, cols]).any(axis=1)
        for ja, jc in _amplitude_centre_pairs(tuple(getattr(self, "feature_names_", ())),
                                                  np.asarray(cols, dtype=bool).tobytes()):
            stated &= ~(np.isfinite(X[:, ja]) & ~np.isfinite(X[:, jc]))
        return stated

    def heads(self, stated: bool):
        """The ``(classifier, regressor)`` that answers recordings of one clearance case."""
        if not stated and self.classifier_no_clearance_ is not None and self.regressor_no_clearance_ is not None:
            return self.classifier_no_clearance_, self.regressor_no_clearance_
        return self.classifier_, self.regressor_

    def __sklearn_tags__(self):
        return _nan_tags(super().__sklearn_tags__())

    def fit(self, X, y, groups=None) -> MisalignmentModel:
        """Fit all components.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features); NaN allowed
        y : array-like of shape (n_samples,)
            True misalignment Δ = δ/c (≥ 0).
        groups : array-like of shape (n_samples,), optional
            Plant identifiers, so that calibration never mixes rows of one plant.
        """
        self.bands_ = SeverityBands(tuple(self.band_edges), tuple(self.band_names))
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan", y_numeric=True)
        y = y.astype(float)
        if self.feature_names is None:
            self.feature_names_ = tuple(f"x{i}" for i in range(X.shape[1]))
        else:
            names = tuple(str(n) for n in self.feature_names)
            if len(names) != X.shape[1]:
                raise ValueError(f"feature_names: {len(names)} names for {X.shape[1]} columns of X")
            if len(set(names)) != len(names):
                raise ValueError("feature_names: names must be unique")
            self.feature_names_ = names
        labels = self.bands_.label(y)
        present = set(labels.tolist())
        missing = [n for n in self.bands_.names if n not in present]
        if missing:
            raise ValueError(
                f"y: the training data has no rows in band(s) {missing}; "
                "every severity band needs examples (check the dataset's Δ range and band_edges)"
            )
        self.classes_ = np.asarray(self.bands_.names, dtype=object)
        self.monotonic_cst_ = self._monotonic_cst()
        self.clearance_columns_ = self._clearance_columns()
        share = float(self.clearance_dropout)
        if not 0.0 <= share <= 1.0:
            raise ValueError(f"clearance_dropout: must lie in [0, 1], got {self.clearance_dropout!r}")
        # What a recording without the clearance looks like, in the seeded share of the rows.
        X_shared = blank_clearance(X, self.clearance_columns_, share, int(self.random_state))
        self.classifier_no_clearance_ = self.regressor_no_clearance_ = None
        if self.clearance_heads:
            if not self.clearance_columns_.any():
                raise ValueError("clearance_heads: needs clearance_features that match feature names")
            self.classifier_, self.regressor_ = self._fit_heads(X, y, groups)
            X_none = blank_clearance(X, self.clearance_columns_, 1.0, 0)
            self.classifier_no_clearance_, self.regressor_no_clearance_ = self._fit_heads(X_none, y, groups)
        else:
            self.classifier_, self.regressor_ = self._fit_heads(X_shared, y, groups)
        self.ood_columns_, self.ood_log_scale_ = self._ood_columns()
        self.ood_ = clone(self.ood if self.ood is not None else KNNDistanceOOD())
        self.ood_.fit(self.ood_input(X_shared), groups=groups)
        self._fit_envelope(X_shared, groups)
        nan = np.isnan(X_shared)
        self.feature_nan_rate_ = nan.mean(axis=0)
        with np.errstate(all="ignore"):
            med = np.nanmedian(np.where(nan.all(axis=0), 0.0, X_shared), axis=0)
        self.feature_median_ = np.where(np.isfinite(med), med, 0.0)
        offsets = self._attitude_offsets(X)
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)           # a bearing never instrumented: NaN
            self.attitude_offset_reference_deg_ = np.nanmedian(offsets, axis=0)
        rows = getattr(self.ood_, "reference_rows_", None)
        self.reference_attitude_offset_deg_ = None if rows is None else offsets[rows].astype(np.float32)
        return self

    def _attitude_offsets(self, X: np.ndarray) -> np.ndarray:
        """Per row and bearing 1–9 (column ``n − 1``), the journal's attitude offset from a plain short journal
        bearing's (``b{n}_attitude_offset_deg``), NaN where undefined (no centreline, eccentricity below
        ``ATTITUDE_MIN_ECC`` or beyond the clearance): the load-line direction the training journals held, which
        ``models.status`` compares a recording's with (a tilting-pad or linear bearing holds its journal on the
        load line, 30–60° off a plain bearing's)."""
        names = list(self.feature_names_)
        out = np.full((X.shape[0], 9), np.nan)
        for b in range(1, 10):
            if f"b{b}_centre_x_per_c" not in names or f"b{b}_centre_y_per_c" not in names:
                continue
            x = X[:, names.index(f"b{b}_centre_x_per_c")]
            y = X[:, names.index(f"b{b}_centre_y_per_c")]
            ecc = np.hypot(x, y)
            ok = np.isfinite(ecc) & (ecc >= ATTITUDE_MIN_ECC) & (ecc <= 1.0)
            out[ok, b - 1] = attitude_offset_deg(x[ok], y[ok], ecc[ok])
        return out

    def attitude_reference_deg(self, row: np.ndarray, n_neighbors: int = NEAREST_TRAINING) -> np.ndarray:
        """Per bearing 1–9 (index ``n − 1``), where the journals of the ``n_neighbors`` training recordings nearest
        to ``row`` sat: their median attitude offset from a plain short bearing's, where at least
        :data:`ATTITUDE_MIN_NEIGHBOURS` of them define it, else the training's overall median
        (``attitude_offset_reference_deg_``). The neighbours are the OOD scorer's (its reference rows and columns,
        which a turned probe frame does not move), so a train whose bearings hold their journals elsewhere than
        the paper plant's is compared with the training trains like it. A model saved before the per-row
        reference existed gives the overall median."""
        check_is_fitted(self, "ood_")
        overall = np.asarray(getattr(self, "attitude_offset_reference_deg_", np.zeros(9)), dtype=float)
        per_row = getattr(self, "reference_attitude_offset_deg_", None)
        if per_row is None or not isinstance(self.ood_, KNNDistanceOOD):
            return overall
        z = self.ood_input(np.asarray(row, dtype=float).reshape(1, -1))[0]
        near = np.asarray(per_row, dtype=float)[self.ood_.nearest_reference(z, n_neighbors)]
        count = np.isfinite(near).sum(axis=0)
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            median = np.nanmedian(near, axis=0)
        return np.where(count >= ATTITUDE_MIN_NEIGHBOURS, median, overall)

    def _fit_heads(self, X: np.ndarray, y: np.ndarray, groups) -> tuple:
        """A fitted (classifier, Δ regressor) pair on rows X."""
        cst = self.monotonic_cst_ if self.monotonic_cst_.any() else None
        clf = clone(self.classifier if self.classifier is not None else SeverityClassifier())
        if isinstance(clf, OrdinalSeverityClassifier):
            # Band indices 0..K−1: numpy's sort order is the bands' order.
            clf.set_params(monotonic_cst=cst)
            # False alarms are bounded on perfectly aligned machines (Δ = 0), not on the aligned
            # band's near-edge rows, which are legitimately close to "slight".
            clf.fit(X, self.bands_.index(y), groups=groups, healthy=(y == 0) if (y == 0).any() else None)
        else:
            if cst is not None:
                raise ValueError("monotonic_increasing: needs an OrdinalSeverityClassifier (a multiclass "
                                 "SeverityClassifier cannot take monotonic constraints)")
            clf.fit(X, self.bands_.label(y), groups=groups)
        reg = clone(self.regressor if self.regressor is not None else ConformalIntervalRegressor(lower_bound=0.0))
        if cst is not None:
            reg.set_params(monotonic_cst=cst)
        reg.fit(X, y, groups=groups)
        return clf, reg

    def _clearance_columns(self) -> np.ndarray:
        return name_mask(self.feature_names_, tuple(str(p) for p in (self.clearance_features or ())))

    def _monotonic_cst(self) -> np.ndarray:
        pats = tuple(str(p) for p in self.monotonic_increasing)
        require_matches("monotonic_increasing", pats, self.feature_names_)
        return name_mask(self.feature_names_, pats).astype(int)

    def _ood_columns(self) -> tuple[np.ndarray, np.ndarray]:
        pats = tuple(str(p) for p in (self.ood_features or ()))
        names = self.feature_names_
        cols = np.arange(len(names)) if not pats else np.flatnonzero(name_mask(names, pats))
        require_matches("ood_features", pats, names)
        scales = dict(self.ood_log_scales or {})
        bad = {p: v for p, v in scales.items() if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0)}
        if bad:
            raise ValueError(f"ood_log_scales: every scale must be a positive number, got {bad}")
        log_scale = np.array([pattern_value(names[j], scales, 0.0) for j in cols], dtype=float)
        return cols, log_scale

    def ood_input(self, X: np.ndarray) -> np.ndarray:
        """The OOD scorer's columns of X (``ood_features``), log-scaled where ``ood_log_scales`` say.

        Models saved before the OOD feature selection existed see every column, unscaled.
        """
        X = np.asarray(X, dtype=float)
        cols = getattr(self, "ood_columns_", None)
        if cols is None:
            return X
        Z = X[:, cols]
        log_cols = self.ood_log_scale_ > 0
        if log_cols.any():
            Z = np.array(Z, copy=True)
            with np.errstate(invalid="ignore"):
                Z[:, log_cols] = np.log1p(np.maximum(Z[:, log_cols], 0.0) / self.ood_log_scale_[log_cols])
        return Z

    # ------------------------------------------------------------------ feature envelope
    _ATTITUDE = re.compile(r"b(\d+)_attitude_(offset_)?deg")

    def _derived_names(self) -> list[str]:
        names = set(self.feature_names_)
        return [f"b{b}_attitude_{kind}deg" for b in range(1, 10) for kind in ("", "offset_")
                if f"b{b}_centre_x_per_c" in names and f"b{b}_centre_y_per_c" in names]

    def _fit_envelope(self, X: np.ndarray, groups) -> None:
        pats = tuple(str(p) for p in (self.envelope_features or ()))
        if not pats:
            self.envelope_ = None
            self.envelope_names_: tuple[str, ...] = ()
            return
        candidates = list(self.feature_names_) + self._derived_names()
        chosen = [n for n, hit in zip(candidates, name_mask(candidates, pats)) if hit]
        require_matches("envelope_features", pats, candidates,
                        " (nor a derived b{n}_attitude_deg / b{n}_attitude_offset_deg)")
        upper = tuple(str(p) for p in (self.envelope_upper_only or ()))
        scales = dict(self.ood_log_scales or {})
        self.envelope_names_ = tuple(chosen)
        self.envelope_log_floor_ = np.array([pattern_value(n, scales, 0.0) * 1e-3 for n in chosen], dtype=float)
        check_low = ~name_mask(chosen, upper)
        self.envelope_ = clone(self.envelope if self.envelope is not None else FeatureEnvelope())
        self.envelope_.fit(self.envelope_input(X), groups=groups, check_low=check_low)

    def envelope_values(self, X: np.ndarray) -> np.ndarray:
        """The envelope's columns of X in their own units (derived attitude offsets computed), (n, q)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        plain_j, plain_cols, derived = _envelope_plan(tuple(str(n) for n in self.feature_names_),
                                                      tuple(str(n) for n in self.envelope_names_))
        out = np.empty((X.shape[0], len(self.envelope_names_)))
        out[:, plain_j] = X[:, plain_cols]
        for j, cx, cy, offset in derived:
            x, y = X[:, cx], X[:, cy]
            ecc = np.hypot(x, y)
            att = attitude_offset_deg(x, y, ecc) if offset else (attitude_angle_deg(x, y) + 180.0) % 360.0 - 180.0
            defined = (ecc >= ATTITUDE_MIN_ECC) & (ecc <= 1.0)
            out[:, j] = np.where(defined, att, np.nan)
        return out

    def envelope_input(self, X: np.ndarray) -> np.ndarray:
        """:meth:`envelope_values`, log10-scaled where ``envelope_log_floor_`` > 0."""
        return self._envelope_log(self.envelope_values(X))

    def _envelope_log(self, V: np.ndarray) -> np.ndarray:
        """``V`` (envelope values, changed in place) log10-scaled where ``envelope_log_floor_`` > 0."""
        logc = self.envelope_log_floor_ > 0
        with np.errstate(invalid="ignore", divide="ignore"):
            V[:, logc] = np.log10(np.maximum(V[:, logc], self.envelope_log_floor_[logc]))
        return V

    def _envelope_excess(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(values, envelope input, excess in spreads) of the envelope columns; a column of
        :data:`ENVELOPE_REL_TOLERANCE` has no excess within its relative tolerance of the training range."""
        env = self.envelope_
        assert env is not None, "no envelope fitted"
        V = self.envelope_values(X)
        Z = self._envelope_log(V.copy())
        exc = env.excess(Z)
        for j, name in enumerate(self.envelope_names_):
            tol = ENVELOPE_REL_TOLERANCE.get(str(name))
            if tol is not None and not self.envelope_log_floor_[j] > 0:
                near = (V[:, j] >= env.lo_[j] * (1.0 - tol)) & (V[:, j] <= env.hi_[j] * (1.0 + tol))
                exc[near, j] = 0.0
        return V, Z, exc

    def envelope_findings(self, X) -> list[list[dict]]:
        """Per row, the envelope features outside the training range, largest excess first.

        Each finding: ``feature``, ``value`` (its own units), ``train_min``, ``train_max``,
        ``side`` (``below`` | ``above``), ``factor`` (how many times beyond the range, for
        log-compared features; else None) and ``excess_spreads``. Empty lists when the model
        has no envelope (saved before it existed, or ``envelope_features`` empty).
        """
        X = np.atleast_2d(np.asarray(X, dtype=float))
        env = getattr(self, "envelope_", None)
        if env is None:
            return [[] for _ in range(X.shape[0])]
        V, Z, exc = self._envelope_excess(X)
        logc = self.envelope_log_floor_ > 0
        lo, hi = env.lo_.astype(float), env.hi_.astype(float)
        lo[logc], hi[logc] = 10.0 ** lo[logc], 10.0 ** hi[logc]
        rows = []
        for i in range(X.shape[0]):
            found = []
            for j in np.argsort(-exc[i], kind="stable"):
                if not exc[i, j] > env.margin_:
                    break
                v = float(V[i, j])
                side = "below" if Z[i, j] < env.lo_[j] else "above"
                factor = None
                if logc[j]:
                    shown = max(v, float(self.envelope_log_floor_[j]))
                    factor = float(lo[j] / shown if side == "below" else shown / hi[j])
                found.append({"feature": self.envelope_names_[j], "value": v, "train_min": float(lo[j]),
                              "train_max": float(hi[j]), "side": side, "factor": factor,
                              "excess_spreads": float(exc[i, j])})
            rows.append(found)
        return rows

    def ood_flags(self, X) -> np.ndarray:
        """Out of distribution: OOD score above 1 or a feature outside the envelope, bool (n,)."""
        flags = self.ood_ratio(X) > 1.0
        env = getattr(self, "envelope_", None)
        if env is not None:
            flags |= (self._envelope_excess(np.atleast_2d(np.asarray(X, dtype=float)))[2] > env.margin_).any(axis=1)
        return flags

    def band_order(self, classifier=None) -> list[int]:
        """Columns of ``classifier``'s (default ``classifier_``) probabilities in band order."""
        clf = self.classifier_ if classifier is None else classifier
        if isinstance(clf, OrdinalSeverityClassifier):
            return list(range(len(self.bands_.names)))
        return [list(clf.classes_).index(n) for n in self.bands_.names]

    def clearance_cases(self, X) -> list[tuple[np.ndarray, bool]]:
        """``(rows, stated)`` for each clearance case present in X: the rows (bool mask) that a
        pair answers, and whether that pair is the clearance-stated one. One case, every row,
        for a model with a single pair."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if self.classifier_no_clearance_ is None:
            return [(np.ones(X.shape[0], dtype=bool), True)]
        stated = self.clearance_stated(X)
        return [(rows, case) for rows, case in ((stated, True), (~stated, False)) if rows.any()]

    def _cases(self, X: np.ndarray):
        """``(rows, classifier, regressor)`` for each clearance case present in X."""
        return [(rows, *self.heads(case)) for rows, case in self.clearance_cases(X)]

    def predict_proba(self, X) -> np.ndarray:
        """Severity probabilities, shape (n_samples, n_bands), columns in band order; each row from
        its clearance case's classifier."""
        check_is_fitted(self, "classifier_")
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan")
        out = np.empty((X.shape[0], len(self.bands_.names)))
        for rows, clf, _ in self._cases(X):
            out[rows] = clf.predict_proba(X[rows])[:, self.band_order(clf)]
        return out

    def predict(self, X) -> np.ndarray:
        """Severity band of each row (array of str): see :meth:`band_index`."""
        return self.classes_[self.band_index(self.predict_proba(X), X)]

    def predict_misalignment(self, X) -> tuple[np.ndarray, np.ndarray]:
        """Δ estimate and its interval: ``(point (n,), interval (n, 2))``, each row from its
        clearance case's regressor."""
        check_is_fitted(self, "regressor_")
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan")
        point, interval = np.empty(X.shape[0]), np.empty((X.shape[0], 2))
        for rows, _, reg in self._cases(X):
            point[rows], interval[rows] = reg.predict(X[rows]), reg.predict_interval(X[rows])
        return point, interval

    def ood_ratio(self, X) -> np.ndarray:
        """OOD distance / threshold per row (> 1: unlike the training data)."""
        check_is_fitted(self, "ood_")
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan")
        return self.ood_.ood_ratio(self.ood_input(X))

    def training_neighbour_values(self, row: np.ndarray, feature: str, n_neighbors: int) -> np.ndarray | None:
        """``feature`` in the ``n_neighbors`` training recordings nearest to ``row`` (the OOD scorer's reference
        rows and columns, ``feature`` itself left out of the distance: :meth:`KNNDistanceOOD.neighbour_values`),
        in the feature's units; None when ``feature`` is not one of the OOD columns or the scorer keeps no
        reference. What machines like this one do at that feature in training — e.g. whether their 1X whirls
        backward at a bearing (``models.checks.backward_whirl``)."""
        check_is_fitted(self, "ood_")
        names = list(self.feature_names_)
        cols = getattr(self, "ood_columns_", None)
        if feature not in names or not isinstance(self.ood_, KNNDistanceOOD):
            return None
        j = names.index(feature)
        ood_cols = list(range(len(names))) if cols is None else [int(c) for c in cols]
        if j not in ood_cols:
            return None
        at = ood_cols.index(j)
        z = self.ood_input(np.asarray(row, dtype=float).reshape(1, -1))[0]
        values = self.ood_.neighbour_values(z, at, n_neighbors)
        log_scale = getattr(self, "ood_log_scale_", None)
        if log_scale is not None and cols is not None and log_scale[at] > 0:
            values = np.expm1(values) * log_scale[at]
        return values


@lru_cache(maxsize=8)
def _envelope_plan(feature_names: tuple[str, ...], envelope_names: tuple[str, ...]
                   ) -> tuple[np.ndarray, np.ndarray, tuple[tuple[int, int, int, bool], ...]]:
    """Where :meth:`MisalignmentModel.envelope_values` finds each envelope column, made once per model's names: the
    plain columns (envelope column, feature column) and the derived attitude angles (envelope column, the bearing's
    centre x and y feature columns, whether the short-bearing attitude is subtracted)."""
    index = {n: i for i, n in enumerate(feature_names)}
    plain_j, plain_cols, derived = [], [], []
    for j, name in enumerate(envelope_names):
        m = MisalignmentModel._ATTITUDE.fullmatch(name)
        if name in index:
            plain_j.append(j)
            plain_cols.append(index[name])
        elif m:
            derived.append((j, index[f"b{m.group(1)}_centre_x_per_c"], index[f"b{m.group(1)}_centre_y_per_c"],
                            bool(m.group(2))))
        else:                                   # pragma: no cover - names come from _fit_envelope
            raise KeyError(name)
    return np.array(plain_j, dtype=np.intp), np.array(plain_cols, dtype=np.intp), tuple(derived)
