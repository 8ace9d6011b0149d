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


def test_a_threshold_on_the_calls_probability_keeps_whole_ties_and_counts_what_it_keeps():
    def o(delta, shown, p):
        out = _outcome(delta, shown, "uncertain")
        out.call_probability = p
        return out

    outs = [o(0.0, "aligned", 0.99), o(0.25, "moderate", 0.95), o(0.40, "severe", 0.95),   # right, right, right
            o(0.10, "aligned", 0.90),                                                       # one band off
            o(0.30, "aligned", 0.80),                                                       # two bands off
            o(0.50, "severe", 0.70), o(0.0, "aligned", 0.60), o(0.12, "slight", 0.50),     # right
            o(0.20, "refused", math.nan), o(0.0, "slight", 0.40)]                           # refused; one off
    rows = dict(tt.selective_rows(BUNDLE, outs))
    assert rows["largest share kept with ≥ 98 % in the true band"] == "30.0 % (3 of 10)"
    assert rows["largest share kept with every answer within one band"] == "40.0 % (4 of 10)"
    # the smallest threshold keeping ≥ 7 of 10: 0.60 keeps 7, 5 of them in the band, 6 within one
    assert rows["in the true band, keeping 70.0 % (7 of 10)"] == "71.4 % (5 of 7)"
    assert rows["within one band, keeping 70.0 % (7 of 10)"] == "85.7 % (6 of 7)"
    tied = [o(0.0, "aligned", 0.9), o(0.3, "aligned", 0.9)] + [o(0.0, "aligned", 0.8)] * 3
    rows = dict(tt.selective_rows(BUNDLE, tied))           # the right one cannot be kept without its tie
    assert rows["largest share kept with ≥ 98 % in the true band"] == "0.0 % (0 of 5)"
    assert rows["in the true band, keeping 100.0 % (5 of 5)"] == "80.0 % (4 of 5)"      # 0.8 keeps all five
    none = [o(0.0, "refused", math.nan)] * 4 + [o(0.0, "aligned", 0.9)]
    assert dict(tt.selective_rows(BUNDLE, none))["kept answers at ≥ 70 % of them"] == "no threshold keeps that many"


def test_an_idealised_estimate_is_right_when_exact_and_less_so_when_noisy():
    outs = [_outcome(d, "aligned", "uncertain") for d in [0.0] * 20 + list(np_linspace(0.01, 0.6, 60))]
    for o in outs:
        o.delta_model = o.delta + 0.05
    rows = tt.precision_rows(BUNDLE, outs, sigmas=(1e-9, 0.05, 0.2), repeats=10, seed=3)
    assert rows[0][0] == "the model: Δ error s.d. 0.000, mean absolute 0.050"
    assert rows[1][1:] == ("100.0 %", "100.0 %")                 # exact: every kept answer in its band
    noisy, noisier = float(rows[2][1].split()[0]), float(rows[3][1].split()[0])
    assert 50.0 < noisier < noisy < 100.0
    assert rows == tt.precision_rows(BUNDLE, outs, sigmas=(1e-9, 0.05, 0.2), repeats=10, seed=3)   # seeded


def np_linspace(a, b, n):
    return [a + (b - a) * k / (n - 1) for k in range(n)]
