"""Fast inference for a fitted :class:`~models.estimators.MisalignmentModel`.

The service answers one recording at a time, and for one row scikit-learn's predict
calls are dominated by per-call overhead (input validation, thread-pool set-up, one
call per boosted model: seven ensembles in all), not by arithmetic. This module
flattens every fitted :class:`~sklearn.ensemble.HistGradientBoostingClassifier` /
``...Regressor`` of the model into plain node arrays and walks them in one compiled
(numba) loop, with the same decision rule as scikit-learn's predictor (``NaN`` goes
to the side the tree learned for missing values, otherwise ``x <= threshold`` goes
left). The calibration map, the conformal interval arithmetic and the OOD distance
are the model's own; only the tree walks and the neighbour search are replaced.

It also makes the verdict's explanation cheap. Occlusion (replace one feature by its
training median, see how much the probability of the verdict drops) needs a
prediction per feature; but replacing feature *j* can only change trees that split
on *j*, so only those are walked again (:func:`occlusion_raw`). The result is the
same as predicting every occluded row, to rounding.

:class:`CompiledModel` gives the same numbers as the model's scikit-learn methods to
~1e-12 (tree sums in a different order) and 1e-5 for the OOD distance (float32
reference set); ``tests/test_models_compiled.py`` checks it on fitted models of every
calibration method.
"""
from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor

from ._columns import _blank  # the estimators' own column blanking (sparse training columns → 0)
from ._sklearn_private import hgb_trees, single_calibration
from .ordinal import OrdinalSeverityClassifier


@dataclass(frozen=True)
class Forest:
    """The trees of one or more boosted ensembles as flat arrays.

    ``output[t]`` is the output column tree ``t`` adds its leaf value to (the class for
    a multiclass classifier; one column per ensemble when several are stacked).
    """

    feature: np.ndarray      # (n_nodes,) int64, -1 at leaves
    threshold: np.ndarray    # (n_nodes,) float64
    missing_left: np.ndarray  # (n_nodes,) bool
    left: np.ndarray         # (n_nodes,) int64, absolute node index
    right: np.ndarray        # (n_nodes,) int64
    value: np.ndarray        # (n_nodes,) float64
    root: np.ndarray         # (n_trees,) int64
    output: np.ndarray       # (n_trees,) int64
    baseline: np.ndarray     # (n_outputs,) float64
    # Trees that split on each feature (CSR): trees_of_feature[ptr[j]:ptr[j+1]].
    feature_ptr: np.ndarray
    trees_of_feature: np.ndarray


def _ensemble_trees(model) -> tuple[list, np.ndarray]:
    """``[(nodes, output column)]`` and the baseline of one fitted HistGradientBoosting model."""
    if not isinstance(model, (HistGradientBoostingClassifier, HistGradientBoostingRegressor)):
        raise TypeError(f"not a HistGradientBoosting model: {type(model).__name__}")
    if getattr(model, "is_categorical_", None) is not None and np.any(model.is_categorical_):
        raise TypeError("categorical features are not supported by the compiled predictor")
    return hgb_trees(model)


def compile_forest(models, n_features: int) -> Forest:
    """Stack fitted HistGradientBoosting models into one :class:`Forest`.

    The outputs of model ``m`` follow those of models ``0..m-1`` (a 4-class classifier
    takes 4 columns, a regressor 1).
    """
    feature, threshold, missing_left, left, right, value = [], [], [], [], [], []
    root, output, baseline = [], [], []
    offset = 0
    col0 = 0
    for model in models:
        trees, base = _ensemble_trees(model)
        for nodes, k in trees:
            n = nodes.shape[0]
            leaf = nodes["is_leaf"].astype(bool)
            feature.append(np.where(leaf, -1, nodes["feature_idx"]).astype(np.int64))
            threshold.append(nodes["num_threshold"].astype(float))
            missing_left.append(nodes["missing_go_to_left"].astype(bool))
            left.append(nodes["left"].astype(np.int64) + offset)
            right.append(nodes["right"].astype(np.int64) + offset)
            value.append(nodes["value"].astype(float))
            root.append(offset)
            output.append(col0 + k)
            offset += n
        baseline.append(base)
        col0 += base.size
    feature_a = np.concatenate(feature)
    root_a = np.asarray(root, np.int64)
    n_trees = root_a.size
    # Feature → trees that split on it.
    ends = np.append(root_a[1:], feature_a.size)
    pairs = set()
    for t in range(n_trees):
        for f in np.unique(feature_a[root_a[t]:ends[t]]):
            if f >= 0:
                pairs.add((int(f), t))
    pair_list = sorted(pairs)
    counts = np.bincount([f for f, _ in pair_list], minlength=n_features)
    ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return Forest(
        feature=feature_a, threshold=np.concatenate(threshold), missing_left=np.concatenate(missing_left),
        left=np.concatenate(left), right=np.concatenate(right), value=np.concatenate(value),
        root=root_a, output=np.asarray(output, np.int64), baseline=np.concatenate(baseline),
        feature_ptr=ptr, trees_of_feature=np.asarray([t for _, t in pair_list], np.int64),
    )


@numba.njit(cache=True, nogil=True)
def _leaf(feature, threshold, missing_left, left, right, value, node, row, j_sub, x_sub):
    """Leaf value of the tree rooted at ``node`` for ``row`` (feature ``j_sub`` read as ``x_sub``)."""
    while feature[node] >= 0:
        f = feature[node]
        x = x_sub if f == j_sub else row[f]
        if np.isnan(x):
            node = left[node] if missing_left[node] else right[node]
        elif x <= threshold[node]:
            node = left[node]
        else:
            node = right[node]
    return value[node]


@numba.njit(cache=True, nogil=True)
def _raw(feature, threshold, missing_left, left, right, value, root, output, baseline, X):
    n = X.shape[0]
    out = np.empty((n, baseline.size))
    for i in range(n):
        row = X[i]
        for k in range(baseline.size):
            out[i, k] = baseline[k]
        for t in range(root.size):
            out[i, output[t]] += _leaf(feature, threshold, missing_left, left, right, value, root[t], row, -1, 0.0)
    return out


@numba.njit(cache=True, nogil=True)
def _occlusion(feature, threshold, missing_left, left, right, value, root, output, baseline,
               ptr, trees_of, row, reference):
    n_out = baseline.size
    base = baseline.copy()
    leaf = np.empty(root.size)
    for t in range(root.size):
        leaf[t] = _leaf(feature, threshold, missing_left, left, right, value, root[t], row, -1, 0.0)
        base[output[t]] += leaf[t]
    n_feat = ptr.size - 1
    out = np.empty((n_feat, n_out))
    for j in range(n_feat):
        for k in range(n_out):
            out[j, k] = base[k]
        for p in range(ptr[j], ptr[j + 1]):
            t = trees_of[p]
            v = _leaf(feature, threshold, missing_left, left, right, value, root[t], row, j, reference[j])
            out[j, output[t]] += v - leaf[t]
    return out


def raw_predict(forest: Forest, X: np.ndarray) -> np.ndarray:
    """Raw outputs (baseline + sum of leaf values), shape (n_samples, n_outputs)."""
    f = forest
    return _raw(f.feature, f.threshold, f.missing_left, f.left, f.right, f.value, f.root, f.output,
                f.baseline, np.ascontiguousarray(X, dtype=float))


def occlusion_raw(forest: Forest, row: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Raw outputs of ``row`` with feature ``j`` alone set to ``reference[j]``, for every ``j``.

    Shape (n_features, n_outputs); equal (to rounding) to :func:`raw_predict` on the
    matrix of occluded rows, but only the trees that split on ``j`` are walked again.
    """
    f = forest
    return _occlusion(f.feature, f.threshold, f.missing_left, f.left, f.right, f.value, f.root, f.output,
                      f.baseline, f.feature_ptr, f.trees_of_feature,
                      np.ascontiguousarray(row, dtype=float), np.ascontiguousarray(reference, dtype=float))


def _calibrated_proba(cc, raw: np.ndarray) -> np.ndarray:
    """``CalibratedClassifierCV(ensemble=False).predict_proba`` from the trees' decision values."""
    method, classes, calibrators, estimator = single_calibration(cc)
    n_classes = classes.shape[0]
    if method == "temperature":
        proba = calibrators[0].predict(raw)
    elif method in ("sigmoid", "isotonic"):
        proba = np.zeros((raw.shape[0], n_classes))
        pos = np.searchsorted(classes, estimator.classes_)
        for class_idx, pred, calibrator in zip(pos, raw.T, calibrators):
            if n_classes == 2:
                class_idx += 1
            proba[:, class_idx] = calibrator.predict(pred)
        if n_classes == 2:
            proba[:, 0] = 1.0 - proba[:, 1]
        else:
            den = proba.sum(axis=1)[:, None]
            proba = np.divide(proba, den, out=np.full_like(proba, 1.0 / n_classes), where=den != 0)
    else:
        raise TypeError(f"calibration method {method!r} is not supported by the compiled predictor")
    proba = np.asarray(proba, dtype=float)
    proba[(1.0 < proba) & (proba <= 1.0 + 1e-5)] = 1.0
    return proba


def _softmax(raw: np.ndarray) -> np.ndarray:
    if raw.shape[1] == 1:   # binary: logistic of the single logit
        p1 = 1.0 / (1.0 + np.exp(-raw[:, 0]))
        return np.column_stack([1.0 - p1, p1])
    z = raw - raw.max(axis=1, keepdims=True)
    e = np.exp(z)
    return e / e.sum(axis=1, keepdims=True)


class _CompiledHead:
    """One (classifier, Δ regressor) pair of the model, flattened."""

    def __init__(self, model, clf, reg) -> None:
        n = len(model.feature_names_)
        self.clf = clf
        self.reg = reg
        self.ordinal = isinstance(clf, OrdinalSeverityClassifier)
        if self.ordinal:
            # One binary ensemble per band edge: its raw column is that edge's decision value.
            self.calibrated = False
            self.clf_forest = compile_forest(list(clf.models_), n)
        else:
            inner = clf.model_
            self.calibrated = bool(clf.calibrated_)
            boosted = inner.calibrated_classifiers_[0].estimator if self.calibrated else inner
            self.clf_forest = compile_forest([boosted], n)
        self.clf_blank = np.asarray(clf.sparse_columns_, bool)
        self.clf_order = np.asarray(model.band_order(clf))
        self.compiled_reg = CompiledRegressor(reg, n)

    def proba_from_raw(self, raw: np.ndarray) -> np.ndarray:
        if self.ordinal:
            return self.clf.proba_from_scores(raw)[:, self.clf_order]
        if self.calibrated:
            proba = _calibrated_proba(self.clf.model_, raw)
        else:
            proba = _softmax(raw)
        return proba[:, self.clf_order]

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        return self.proba_from_raw(raw_predict(self.clf_forest, _blank(X, self.clf_blank)))

    def predict_misalignment(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.compiled_reg.predict_interval(X)


class CompiledRegressor:
    """One fitted ``ConformalIntervalRegressor`` flattened: its point, centre and scale ensembles in one forest, the
    conformal arithmetic its own (``ConformalIntervalRegressor.predict_interval``). Rows in the regressor's feature
    order (``n_features`` columns), not validated."""

    def __init__(self, reg, n_features: int) -> None:
        self.reg = reg
        parts = [reg.point_model_, reg.center_model_] + ([reg.scale_model_] if reg.scale_model_ is not None else [])
        self.forest = compile_forest(parts, n_features)
        self.blank = np.asarray(reg.sparse_columns_, bool)

    def raw(self, X: np.ndarray) -> np.ndarray:
        """The ensembles' raw outputs, (n, 2 or 3): point, centre (and the residual scale)."""
        return raw_predict(self.forest, _blank(X, self.blank))

    def predict_interval(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(point (n,), interval (n, 2))`` as the regressor's ``predict`` and ``predict_interval``."""
        reg = self.reg
        raw = self.raw(X)
        clip = (lambda v: v) if reg.lower_bound is None else (lambda v: np.maximum(v, reg.lower_bound))
        point = clip(raw[:, 0])
        centre = raw[:, 1]
        scale = np.maximum(raw[:, 2], reg.scale_floor_) if raw.shape[1] > 2 else np.full(len(X), reg.scale_floor_)
        with np.errstate(invalid="ignore"):
            half = reg.conformity_quantile_ * scale
        lo = np.minimum(centre - half, point)
        hi = np.maximum(centre + half, point)
        return point, np.column_stack([clip(lo), clip(hi)])


class CompiledModel:
    """The inference methods of a fitted ``MisalignmentModel``, without per-call overhead.

    Parameters
    ----------
    model : fitted models.estimators.MisalignmentModel

    Notes
    -----
    Inputs are not validated beyond shape: callers (:func:`models.pipeline.diagnose_recording`)
    build rows in the model's feature order. A model with a pair per clearance case
    (``clearance_heads``) answers each row with its case's pair, as the model does.
    """

    def __init__(self, model) -> None:
        self.model = model
        self.n_features = len(model.feature_names_)
        self._heads = {True: _CompiledHead(model, *model.heads(True))}
        if getattr(model, "classifier_no_clearance_", None) is not None:
            self._heads[False] = _CompiledHead(model, *model.heads(False))
        ood = model.ood_
        imputer, scaler = ood.preprocess_.named_steps["impute"], ood.preprocess_.named_steps["scale"]
        self._ood_fill = np.asarray(imputer.statistics_, float)
        n_ood = self._ood_fill.shape[0]        # the OOD scorer's own columns (model.ood_input)
        self._ood_mean = np.asarray(scaler.mean_, float) if scaler.with_mean else np.zeros(n_ood)
        self._ood_scale = np.asarray(scaler.scale_, float) if scaler.with_std else np.ones(n_ood)
        self._ood_ref = np.asarray(ood.reference_, np.float32)
        self._ood_ref_sq = np.einsum("ij,ij->i", self._ood_ref.astype(float), self._ood_ref.astype(float))

    # -- helpers ---------------------------------------------------------------------------------
    def _rows(self, X) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        if X.ndim == 1:
            X = X[None, :]
        if X.ndim != 2 or X.shape[1] != self.n_features:
            raise ValueError(f"X: expected (n_samples, {self.n_features}) features, got shape {X.shape}")
        if np.isinf(X).any():   # as scikit-learn's validation (NaN = missing is fine, infinity is not)
            raise ValueError("Input X contains infinity or a value too large for dtype('float64').")
        return X

    def _cases(self, X: np.ndarray) -> list[tuple[np.ndarray, _CompiledHead]]:
        return [(rows, self._heads[stated]) for rows, stated in self.model.clearance_cases(X)]

    # -- the model's methods ---------------------------------------------------------------------
    def predict_proba(self, X) -> np.ndarray:
        """Severity probabilities in band order (as ``MisalignmentModel.predict_proba``)."""
        X = self._rows(X)
        out = np.empty((X.shape[0], len(self.model.bands_.names)))
        for rows, head in self._cases(X):
            out[rows] = head.predict_proba(X[rows])
        return out

    def predict_misalignment(self, X) -> tuple[np.ndarray, np.ndarray]:
        """Δ point estimate and conformal interval (as ``MisalignmentModel.predict_misalignment``)."""
        X = self._rows(X)
        point, interval = np.empty(X.shape[0]), np.empty((X.shape[0], 2))
        for rows, head in self._cases(X):
            point[rows], interval[rows] = head.predict_misalignment(X[rows])
        return point, interval

    def ood_ratio(self, X) -> np.ndarray:
        """k-th-neighbour distance / threshold (as ``MisalignmentModel.ood_ratio``)."""
        ood = self.model.ood_
        X = self.model.ood_input(self._rows(X))
        X = np.where(np.isnan(X), self._ood_fill, X)
        Z = ((X - self._ood_mean) / self._ood_scale).astype(np.float32).astype(float)
        # ‖z − r‖² = ‖z‖² − 2 z·r + ‖r‖², clipped at 0 against rounding.
        d2 = (Z * Z).sum(axis=1)[:, None] - 2.0 * Z @ self._ood_ref.T.astype(float) + self._ood_ref_sq[None, :]
        k = ood.k_
        kth = np.sqrt(np.maximum(np.partition(d2, k - 1, axis=1)[:, k - 1], 0.0))
        return kth / max(ood.threshold_, np.finfo(float).tiny)

    def occlusion_proba(self, row: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Probabilities of ``row`` and of ``row`` with each feature set to its training median.

        The row's clearance case (so its classifier) is that of ``row`` itself: setting one
        feature to its median explains the answer the row got, it does not switch cases.

        Returns
        -------
        base : ndarray (n_bands,)
        occluded : ndarray (n_features, n_bands)
            Row ``j``: probabilities with feature ``j`` replaced by ``feature_median_[j]``.
        """
        X = self._rows(row)
        head = self._cases(X[:1])[0][1]
        X = _blank(X, head.clf_blank)
        ref = self.model.feature_median_.astype(float).copy()
        ref[head.clf_blank] = 0.0   # a blanked column is 0 whatever it is replaced with
        raw_base = raw_predict(head.clf_forest, X)
        base = head.proba_from_raw(raw_base)[0]
        raw = occlusion_raw(head.clf_forest, X[0], ref)
        # Features whose replacement moves no tree leave the raw scores, so the probabilities, as they were.
        changed = np.any(raw != raw_base, axis=1)
        occluded = np.repeat(base[None, :], raw.shape[0], axis=0)
        if changed.any():
            occluded[changed] = head.proba_from_raw(raw[changed])
        return base, occluded
