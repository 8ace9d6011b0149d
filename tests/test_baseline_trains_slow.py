"""Asset baselines on a small shaft train (issue 48, item 4), reproducing ``benchmarks/bench_baseline_trains.py`` on
its smallest machine with fewer baselines: a coupling offset of a few µm moves the journals by a few µm, under the
fleet-wide centreline threshold and far above the machine's own repeatability."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parent.parent / "benchmarks" / "bench_baseline_trains.py"


def _bench():
    if "bench_baseline_trains" in sys.modules:
        return sys.modules["bench_baseline_trains"]
    spec = importlib.util.spec_from_file_location("bench_baseline_trains", BENCH)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules["bench_baseline_trains"] = mod
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow
def test_small_train_offset_of_a_few_um_is_detected_with_its_own_thresholds_only():
    from rotordiag.models.change import shipped_rule

    b = _bench()
    r = b.evaluate("gen50_2pole", 3000.0, draws=10, seed=b.SEED)
    sims = r["sims"]
    moved = {float(sims["offset_um"][i]): r["moved"][i][0] for i in r["misaligned"]}   # last direction per offset
    # a static offset far below the clearance (250 µm) moves the journals in proportion to it
    ratio = np.array([moved[o] / o for o in b.OFFSETS_UM])
    assert ratio.max() / ratio.min() < 1.15, ratio
    shipped_dc = shipped_rule().thresholds["dc_shift_um"]
    for off in (2.0, 5.0):
        assert moved[off] < shipped_dc                          # "a few µm": under the fleet-wide threshold
        assert np.mean(r["det"][("shipped", off)]) == 0.0
        assert np.mean(r["det"][("own", off)]) >= 0.9, (off, r["det"][("own", off)])
    for off in (20.0, 40.0):                                    # well above it: both detect
        assert np.mean(r["det"][("shipped", off)]) == 1.0 and np.mean(r["det"][("own", off)]) == 1.0
    assert np.mean(r["fa"]["own"]) <= 0.10 and len(r["fa"]["own"]) == 10 * (b.N_HEALTHY - b.N_BASE)
