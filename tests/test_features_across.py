"""Columns across bearings (features._across): ratios and differences of two bearings' static positions and orbit
sizes, checked against positions and orbits written into synthetic probe signals."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import extract_features

from .test_features_synth import make_recording

SPEED_RPM = 1953.7
CLEARANCE_UM = 200.0
#: forward circular 1X and 2X orbits (zero-to-peak radius, µm) and the journal's static position (µm) per bearing
ORBITS = {1: (20.0, 2.0), 2: (40.0, 6.0), 3: (10.0, 3.0)}
POSITIONS_UM = {1: (-30.0, -80.0), 2: (-20.0, -120.0), 3: (10.0, -40.0)}


def _circle(r: float, k: int) -> tuple:
    return (k, r, 0.0, r, 90.0)               # x = r cos kθ, y = r sin kθ: forward, major axis 2r pk-pk


def _recording(positions_um: dict = POSITIONS_UM, **kw):
    comps = {b: [_circle(r1, 1), _circle(r2, 2)] for b, (r1, r2) in ORBITS.items()}
    return make_recording(components=comps, speed_rpm=SPEED_RPM,
                          extra=lambda t, b: (np.full_like(t, positions_um[b][0]), np.full_like(t, positions_um[b][1])),
                          **kw)


def test_positions_and_orbits_compared_across_the_coupling_and_along_each_rotor():
    fr = extract_features(_recording(clearance_um=CLEARANCE_UM))
    (x2, y2), (x3, y3), (x1, y1) = POSITIONS_UM[2], POSITIONS_UM[3], POSITIONS_UM[1]
    assert fr["dcentre_x_b2_b3_per_c"] == pytest.approx((x2 - x3) / CLEARANCE_UM, abs=1e-6)
    assert fr["dcentre_y_b2_b3_per_c"] == pytest.approx((y2 - y3) / CLEARANCE_UM, abs=1e-6)
    assert fr["dcentre_y_b2_b1_per_c"] == pytest.approx((y2 - y1) / CLEARANCE_UM, abs=1e-6)
    assert fr["centre_ecc_b2_b3_ratio"] == pytest.approx(np.hypot(x2, y2) / np.hypot(x3, y3), rel=1e-6)
    assert fr["centre_ecc_b2_b1_ratio"] == pytest.approx(np.hypot(x2, y2) / np.hypot(x1, y1), rel=1e-6)
    assert fr["1x_major_b2_b3_ratio"] == pytest.approx(40.0 / 10.0, rel=1e-6)
    assert fr["2x_major_b2_b3_ratio"] == pytest.approx(6.0 / 3.0, rel=1e-6)
    assert fr["1x_major_b2_b1_ratio"] == pytest.approx(40.0 / 20.0, rel=1e-6)
    assert fr["2x_major_b2_b1_ratio"] == pytest.approx(6.0 / 2.0, rel=1e-6)
    # bearing 4 is not recorded: its pair is missing, not a number
    assert all(np.isnan(fr[n]) for n in ("centre_ecc_b3_b4_ratio", "dcentre_x_b3_b4_per_c", "1x_major_b3_b4_ratio"))


def test_positions_need_the_clearance_the_orbit_ratios_do_not():
    fr = extract_features(_recording())
    assert np.isnan(fr["centre_ecc_b2_b3_ratio"]) and np.isnan(fr["dcentre_y_b2_b3_per_c"])
    assert fr["1x_major_b2_b3_ratio"] == pytest.approx(4.0, rel=1e-6)


def test_a_journal_at_the_bearing_centre_gives_a_large_finite_ratio():
    fr = extract_features(_recording({**POSITIONS_UM, 3: (0.0, 0.0)}, clearance_um=CLEARANCE_UM))
    ecc2 = np.hypot(*POSITIONS_UM[2]) / CLEARANCE_UM
    assert fr["centre_ecc_b2_b3_ratio"] == pytest.approx(ecc2 / 1e-3, rel=1e-3)


def test_the_evidence_names_the_load_sharing_between_journals():
    from rotordiag.features import evidence

    items = [it for it in evidence(extract_features(_recording(clearance_um=CLEARANCE_UM)))
             if it.name == "load sharing (centreline)"]
    assert [it.scope for it in items] == ["journals 2 and 3", "journals 2 and 1"]      # bearing 4 not recorded
    ratio = np.hypot(*POSITIONS_UM[2]) / np.hypot(*POSITIONS_UM[3])
    assert items[0].number == pytest.approx(ratio, rel=1e-6)
    assert f"{ratio:.2f}×" in items[0].value and "0.40 c lower, 0.15 c towards −x" in items[0].value
    # without the clearance the positions are not read, and nothing is said about them
    assert not [it for it in evidence(extract_features(_recording())) if it.name == "load sharing (centreline)"]
