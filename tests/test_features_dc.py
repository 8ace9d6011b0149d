"""Recordings whose DC part is no shaft position (stop 36): channels averaging to zero (AC-coupled, or the means
removed) or flagged ``Recording.dc_removed`` have no centreline features, say so, and the evidence says why."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording, evidence, extract_features
from tests.service_util import simulated_channels


@pytest.fixture(scope="module")
def sim():
    return simulated_channels(misalignment=0.0)


def _rec(channels, fs, shift=None, **kw):
    return Recording(fs, [ProbeChannel(b, a, "um", d if shift is None else shift(d)) for b, a, d in channels],
                     speed_rpm=1800.0, clearance_um=350.0, **kw)


def test_zero_mean_channels_and_the_flag_leave_the_centreline_missing(sim):
    fs, ch = sim
    dc = extract_features(_rec(ch, fs))
    ac = extract_features(_rec(ch, fs, shift=lambda d: d - d.mean()))
    flagged = extract_features(_rec(ch, fs, dc_removed=True))
    for b in (1, 2, 3, 4):
        assert np.isfinite(dc[f"b{b}_centre_ecc_per_c"])
        for fr in (ac, flagged):
            assert all(np.isnan(fr[f"b{b}_centre_{q}_per_c"]) for q in ("x", "y", "ecc"))
            # the vibration features stay
            assert fr[f"b{b}_1x_major_pp_per_c"] == pytest.approx(dc[f"b{b}_1x_major_pp_per_c"], rel=1e-6)
    assert "no_dc_position" not in {w.code for w in dc.warnings}
    assert any(w.code == "no_dc_position" and w.values["why"].startswith("every channel averages to zero")
               for w in ac.warnings)
    assert any(w.code == "no_dc_position" and w.values["why"] == "dc_removed" for w in flagged.warnings)
    items = {(e.scope, e.name): e for e in evidence(ac)}
    assert items[("bearing 2", "shaft centreline")].value == "not measured: the channels carry no DC position"
    assert "eccentricity" in {(e.scope, e.name): e for e in evidence(dc)}[("bearing 2", "shaft centreline")].value


def test_a_small_real_dc_is_a_position(sim):
    """A journal near the centre of its bearing is a position: only means zero within DC_REMOVED_MAX_REL of the
    largest peak-to-peak are read as removed."""
    from rotordiag.features import _config as cfg

    fs, ch = sim
    scale = max(float(np.ptp(d)) for _, _, d in ch)
    near = extract_features(_rec(ch, fs, shift=lambda d: d - d.mean() + 20 * cfg.DC_REMOVED_MAX_REL * scale))
    assert np.isfinite(near["b2_centre_ecc_per_c"]) and near["b2_centre_ecc_per_c"] < 0.01
    assert "no_dc_position" not in {w.code for w in near.warnings}


def test_dc_removed_must_be_a_bool(sim):
    fs, ch = sim
    with pytest.raises(ValueError, match="dc_removed"):
        _rec(ch, fs, dc_removed="yes")

