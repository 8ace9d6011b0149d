"""benchmarks/train_targets.py counts what issue 48's held-out-train targets count (hand-made outcomes)."""
from __future__ import annotations

import math
from types import SimpleNamespace

from rotordiag.models.robustness import Outcome

from .bench_util import load_benchmark

tt = load_benchmark("train_targets")

BANDS = SimpleNamespace(names=("aligned", "slight", "moderate", "severe"), edges=(0.05, 0.15, 0.35))
BUNDLE = SimpleNamespace(model=SimpleNamespace(bands_=BANDS))


def _outcome(delta: float, shown: str, status: str, interval=(0.0, 0.6), direction_deg=math.nan, dc=False) -> Outcome:
    o = Outcome(delta, "rigid", model_class=shown, severity=shown, status=status, interval=interval)
    o.direction_deg, o.dc_available = direction_deg, dc
    return o


def test_each_target_counts_its_own_answers():
    outs = [
        _outcome(0.0, "aligned", "confident", (0.0, 0.03)),                 # right, covered
        _outcome(0.0, "slight", "uncertain", (0.02, 0.1)),                  # a false alarm, not confident; not covered
        _outcome(0.25, "moderate", "confident", (0.2, 0.3), 100.0, True),   # right band; direction 10° off
        _outcome(0.40, "moderate", "confident", (0.3, 0.5), 250.0, True),   # one band off; direction 160° off
        _outcome(0.20, "aligned", "confident", (0.0, 0.1)),                 # two bands off; missed; not covered
        _outcome(0.10, "slight", "uncertain", (math.nan, math.nan)),        # no interval: not counted for coverage
    ]
    samples = [{"offset_angle_rad": math.radians(a)} for a in (0.0, 0.0, 90.0, 90.0, 0.0, 0.0)]
    rows = {name: measured for name, measured, _ in tt.target_rows(BUNDLE, samples, outs)}
    assert rows["confident answers"] == "66.7 % (4 of 6)"
    assert rows["confident answers in the true band"] == "50.0 % (2 of 4)"
    assert rows["confident answers within one band"] == "75.0 % (3 of 4)"
    assert rows["false alarms (healthy, any class but aligned)"] == "50.0 % (1 of 2)"
    assert rows["Δ ≥ 0.15 given slight or worse"] == "66.7 % (2 of 3)"
    assert rows["90 % interval covers the true Δ"] == "60.0 % (3 of 5)"
    assert rows["direction within 45° (confident, Δ ≥ 0.15, DC)"] == "50.0 % (1 of 2)"
