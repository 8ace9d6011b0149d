"""Column blanking shared by the severity classifiers and regressors (``models.estimators``, ``models.ordinal``)
and the compiled predictor (``models.compiled``): a training column too sparse for the boosted trees is set to 0."""
from __future__ import annotations

import numpy as np

__all__ = ["MIN_FINITE_PER_COLUMN", "_sparse_columns", "_blank"]

#: a training column with fewer finite values than this is blanked (set to 0)
MIN_FINITE_PER_COLUMN = 10


def _sparse_columns(X: np.ndarray) -> np.ndarray:
    """Columns with fewer than ``MIN_FINITE_PER_COLUMN`` finite values (or all, if fewer rows).

    The boosted trees cannot bin a column that is all NaN (scikit-learn 1.9 raises), which a
    rarely defined feature can be inside one cross-validation fold; such columns are too
    sparse to learn from anyway and are replaced by a constant.
    """
    need = min(MIN_FINITE_PER_COLUMN, X.shape[0])
    return np.isfinite(X).sum(axis=0) < need


def _blank(X: np.ndarray, columns: np.ndarray) -> np.ndarray:
    if not columns.any():
        return X
    X = np.array(X, dtype=float, copy=True)
    X[:, columns] = 0.0
    return X
