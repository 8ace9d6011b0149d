"""Every use of scikit-learn's private internals, in one place.

The compiled verdict path (:mod:`rotordiag.models.compiled`) walks the fitted trees of
``HistGradientBoosting*`` models and replays ``CalibratedClassifierCV``'s calibration map;
the estimators declare their parameters with scikit-learn's own validation helpers; the
model registry trusts a few private scikit-learn classes that fitted models contain.
None of these are public API, so a scikit-learn release may change them:
:func:`check_internals` (run by ``tests/test_models_sklearn_private.py``) fails with a
message naming what changed.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor
from sklearn.utils._param_validation import Interval, StrOptions

__all__ = ["Interval", "StrOptions", "PRIVATE_TRUSTED_TYPES", "SKLEARN_RENAMED_TYPES", "hgb_trees", "single_calibration",
           "check_internals", "TREE_NODE_FIELDS"]

#: private scikit-learn classes that a fitted rotordiag model holds (skops trusted types)
PRIVATE_TRUSTED_TYPES: tuple[str, ...] = (
    "sklearn.calibration._CalibratedClassifier",
    "sklearn.calibration._SigmoidCalibration",
    "sklearn.calibration._TemperatureScaling",
    "sklearn.ensemble._hist_gradient_boosting.predictor.TreePredictor",
    # HistGradientBoosting's compiled losses: trusted by skops' defaults under scikit-learn >= 1.9,
    # not under 1.8 (there the class reports the module ``_loss``; see SKLEARN_RENAMED_TYPES)
    "sklearn._loss._loss.CyHalfBinomialLoss",
    "sklearn._loss._loss.CyHalfMultinomialLoss",
    "sklearn._loss._loss.CyHalfSquaredError",
)
#: scikit-learn 1.8's compiled loss classes report ``__module__ == "_loss"`` (fixed in 1.9), so a model
#: written under 1.8 names them ``_loss.CyHalfSquaredError`` etc., which 1.9 cannot import. Loading
#: rewrites exactly these names (a fixed table) to ``sklearn._loss._loss.*``, importable under both.
SKLEARN_RENAMED_TYPES: dict[str, str] = {
    f"_loss.{cls}": f"sklearn._loss._loss.{cls}"
    for cls in ("CyHalfBinomialLoss", "CyHalfMultinomialLoss", "CyHalfSquaredError")
}
#: fields of a ``TreePredictor.nodes`` record the compiled predictor reads
TREE_NODE_FIELDS: tuple[str, ...] = ("is_leaf", "feature_idx", "num_threshold", "missing_go_to_left",
                                     "left", "right", "value")


def hgb_trees(model: HistGradientBoostingClassifier | HistGradientBoostingRegressor
              ) -> tuple[list[tuple[np.ndarray, int]], np.ndarray]:
    """``[(nodes, output column)]`` of every tree, and the baseline, of a fitted HistGradientBoosting model.

    Reads the private ``_predictors`` (per iteration, one ``TreePredictor`` per output) and
    ``_baseline_prediction``.
    """
    trees = []
    for iteration in model._predictors:
        for k, predictor in enumerate(iteration):
            trees.append((predictor.nodes, k))
    return trees, np.asarray(model._baseline_prediction, dtype=float).ravel()


def single_calibration(calibrated_cv: Any) -> tuple[str, np.ndarray, list, Any]:
    """``(method, classes, calibrators, estimator)`` of a ``CalibratedClassifierCV(ensemble=False)``.

    Reads the private ``_CalibratedClassifier`` held in ``calibrated_classifiers_[0]``.
    """
    cal = calibrated_cv.calibrated_classifiers_[0]
    return cal.method, cal.classes, list(cal.calibrators), cal.estimator


def check_internals() -> None:
    """Fit tiny models and check every internal this package relies on still exists.

    Raises
    ------
    RuntimeError
        Naming the internal that changed and the scikit-learn version, so that an upgrade
        fails with a clear message instead of wrong verdicts.
    """
    import importlib

    import sklearn
    from sklearn.calibration import CalibratedClassifierCV

    def fail(what: str) -> None:
        raise RuntimeError(f"scikit-learn {sklearn.__version__} changed a private internal rotordiag uses: {what}; "
                           "see rotordiag/models/_sklearn_private.py")

    rng = np.random.default_rng(0)
    X = rng.normal(size=(60, 3))
    y = (X[:, 0] > 0).astype(int) + (X[:, 1] > 0.5)
    for est in (HistGradientBoostingClassifier(max_iter=3), HistGradientBoostingRegressor(max_iter=3)):
        est.fit(X, y)
        for attr in ("_predictors", "_baseline_prediction"):
            if not hasattr(est, attr):
                fail(f"{type(est).__name__}.{attr} is gone")
        trees, base = hgb_trees(est)
        names = trees[0][0].dtype.names or ()
        missing = [f for f in TREE_NODE_FIELDS if f not in names]
        if missing:
            fail(f"TreePredictor.nodes lacks fields {missing}")
        if base.size != (est.n_trees_per_iteration_ if hasattr(est, "n_trees_per_iteration_") else 1):
            fail("_baseline_prediction has an unexpected size")
    for method in ("sigmoid", "temperature"):
        try:
            cc = CalibratedClassifierCV(HistGradientBoostingClassifier(max_iter=3), method=method, cv=2,
                                        ensemble=False).fit(X, y)
        except ValueError as exc:
            fail(f"CalibratedClassifierCV(method={method!r}) ({exc})")
        try:
            m, classes, calibrators, _ = single_calibration(cc)
        except AttributeError as exc:
            fail(f"_CalibratedClassifier attributes ({exc})")
        if m != method or len(classes) != 3 or not calibrators or not hasattr(calibrators[0], "predict"):
            fail(f"_CalibratedClassifier for method {method!r} looks different")
    for name in PRIVATE_TRUSTED_TYPES:
        module, cls = name.rsplit(".", 1)
        if not hasattr(importlib.import_module(module), cls):
            fail(f"{name} no longer exists (trusted type of the model registry)")
    if not callable(Interval) or not callable(StrOptions):
        fail("sklearn.utils._param_validation.Interval/StrOptions")
