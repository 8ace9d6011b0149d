"""Coordinate ascent of thresholds on candidate grids (shared by the ordinal classifier's edge tuning and
the rule-of-thumb baseline's cut search)."""
from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

__all__ = ["coordinate_ascent"]


def coordinate_ascent(score: Callable[[np.ndarray], float], start: np.ndarray,
                      candidates: Callable[[int, np.ndarray], Iterable[float]], *, n_passes: int,
                      tol: float) -> tuple[np.ndarray, float]:
    """Maximise ``score`` over a threshold vector one coordinate at a time.

    Each pass tries, for every coordinate ``k`` in order, each value of ``candidates(k, current)``
    and keeps a trial that beats the best score by more than ``tol`` (greedy: later trials start
    from it). Stops after ``n_passes`` passes or a pass without improvement. Deterministic: ties
    keep the earlier value, and the start wins ties.

    Returns
    -------
    (thresholds, score)
    """
    best = np.asarray(start, dtype=float).copy()
    best_score = score(best)
    for _ in range(n_passes):
        moved = False
        for k in range(best.size):
            for t in candidates(k, best):
                trial = best.copy()
                trial[k] = t
                s = score(trial)
                if s > best_score + tol:
                    best, best_score, moved = trial, s, True
        if not moved:
            break
    return best, best_score
