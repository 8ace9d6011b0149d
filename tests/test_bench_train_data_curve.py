"""benchmarks/train_data_curve.py's figures per coupling (hand-made estimates)."""
from __future__ import annotations

import numpy as np
import pytest

from .bench_util import load_benchmark

dc = load_benchmark("train_data_curve")


def test_each_coupling_is_judged_with_the_healthy_trains_and_only_its_own():
    y = np.array([0.0, 0.0, 0.2, 0.4, 0.1, 0.3, 0.5])
    mech = np.array(["aligned", "aligned", "rigid", "rigid", "rigid", "flexible", "flexible"], dtype=object)
    pred = np.array([0.02, 0.30, 0.25, 0.35, 0.10, 0.30, 0.50])
    out = dc.coupling_errors(y, pred, mech)
    assert sorted(out) == ["flexible", "rigid"]
    rigid_err = np.array([0.02, 0.30, 0.05, -0.05, 0.0])
    assert out["rigid"][:2] == pytest.approx((np.mean(np.abs(rigid_err)), np.std(rigid_err)))
    # healthy 0.02, 0.30 against Δ ≥ 0.15 at 0.25, 0.35 (Δ 0.1 is neither): 3 of 4 pairs ordered → AUC 0.75
    assert out["rigid"][2] == pytest.approx(0.75)
    assert out["flexible"][2] == pytest.approx(0.875)          # 0.30 healthy ties 0.30 at Δ 0.3: half a pair
    only = dc.coupling_errors(y, np.where(mech == "rigid", np.nan, pred), mech, ("flexible",))
    assert list(only) == ["flexible"] and only["flexible"] == out["flexible"]      # the other coupling's NaN unread
