"""benchmarks/ross_retrain.py: the Spearman ceiling that ties in the true Δ put on an untied estimate, and the
figures beside it that do not hinge on the ties (hand-made estimates)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import spearmanr

from .bench_util import load_benchmark

rr = load_benchmark("ross_retrain")

#: the ROSS sets' design per machine: 16 healthy, three recordings at each of five Δ levels
DELTA = np.array([0.0] * 16 + [v for v in (0.1, 0.2, 0.3, 0.45, 0.6) for _ in range(3)])


def test_the_ceiling_is_what_any_untied_perfectly_ordered_estimate_reaches():
    ceiling = rr.spearman_ceiling(DELTA)
    assert ceiling == pytest.approx(0.9268, abs=1e-4)
    rng = np.random.default_rng(0)
    for _ in range(5):                                    # any spread inside the tie groups: the same value
        est = DELTA + 1e-3 * rng.random(DELTA.size)
        assert spearmanr(est, DELTA).statistic == pytest.approx(ceiling)
    assert spearmanr(np.maximum(DELTA, 0.0), DELTA).statistic == pytest.approx(1.0)   # tied healthy: above it
    assert rr.spearman_ceiling(np.linspace(0.0, 0.6, 31)) == pytest.approx(1.0)       # no ties, no ceiling


def test_the_tie_free_figures():
    est = DELTA + np.where(DELTA == 0, np.linspace(0.0, 0.05, DELTA.size), 0.0)
    est[-1] = 0.01                   # the last 0.6 read as 0.01: above 6 healthy, level with one, below 9
    f = rr.tie_free_figures(DELTA, est)
    assert f["spearman_misaligned"] == pytest.approx(spearmanr(est[16:], DELTA[16:]).statistic)
    assert f["spearman_misaligned_ceiling"] == pytest.approx(0.9820, abs=1e-4)      # three per level
    n_pos, n_neg = int(np.sum(DELTA >= 0.15)), 16        # 12 against 16: 9.5 of the 192 pairs out of order
    assert f["auc_healthy_moderate"] == pytest.approx(1.0 - 9.5 / (n_pos * n_neg))
    assert rr.tie_free_figures(np.zeros(4), np.arange(4.0))["auc_healthy_moderate"] is None
