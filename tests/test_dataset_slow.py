"""Slow: a dataset with the paper's 400 transient revolutions labels motion as MODEL.md reports."""
from __future__ import annotations

import pytest

from rotordiag.simulator.dataset import DatasetReader, generate

SPEC = """
[design]
method = "grid"
seed = 1
[operating]
speed_rpm = [1500.0, 2600.0]
misalignment = [0.02, 0.2]
mechanism = ["pin", "rigid"]
[measurement]
sample_rate_hz = 2560.0
duration_revs = 8
[simulation]
transient_revs = 400
record_revs_min = 48
"""


@pytest.mark.slow
def test_motion_labels_follow_the_oil_whip_threshold(tmp_path):
    """MODEL.md §6: period-1 from 1200 to ≈ 2200 r/min, oil whip (non-periodic) above ≈ 2350 r/min."""
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    s = generate(spec, tmp_path / "d.h5", n_workers=0, progress=False)
    assert s.complete and s.status_counts == {"ok": 8}
    with DatasetReader(tmp_path / "d.h5") as ds:
        lab = ds.labels()
    for speed, motion in zip(lab["speed_rpm"], lab["motion"]):
        if speed < 2000:
            assert motion == "period-1"
        else:
            assert motion in {"quasi-periodic", "chaotic"} or not motion.startswith("period-1")
