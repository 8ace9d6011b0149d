"""The shaft ends across the coupling (``features._coupling``): exact on constructed signals, and equal to
the offset δ on the simulator's three kinematic mechanisms (an independent statement: the coupling
constraint of docs/model.md, not the features code)."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag import simulator
from rotordiag.features import ProbeChannel, Recording, evidence, extract_features
from rotordiag.features._coupling import COUPLING_FEATURES

FS, N, RPM = 5120.0, 16384, 1953.7
CLEARANCE_UM = 200.0


def _recording(xy_by_bearing: dict[int, tuple[np.ndarray, np.ndarray]], **kw) -> Recording:
    chans = []
    for b, (x, y) in sorted(xy_by_bearing.items()):
        for a in (45.0, 135.0):
            r = np.deg2rad(a)
            chans.append(ProbeChannel(b, a, "um", x * np.cos(r) + y * np.sin(r)))
    kw.setdefault("speed_rpm", RPM)
    kw.setdefault("clearance_um", CLEARANCE_UM)
    return Recording(sample_rate_hz=FS, channels=chans, **kw)


def _shaft(theta: np.ndarray, mean=(0.0, -60.0)) -> tuple[np.ndarray, np.ndarray]:
    """A journal's own motion: 1X ellipse, some 2X, a static position."""
    x = mean[0] + 20.0 * np.cos(theta - 0.3) + 3.0 * np.cos(2 * theta + 1.0)
    y = mean[1] + 12.0 * np.sin(theta + 0.2) + 2.0 * np.sin(2 * theta - 0.5)
    return x, y


def _theta() -> np.ndarray:
    return 2 * np.pi * RPM / 60.0 * np.arange(N) / FS


def test_static_offset_across_the_coupling():
    th = _theta()
    x2, y2 = _shaft(th, mean=(10.0, -70.0))
    x3, y3 = _shaft(th, mean=(-14.0, -38.0))          # same motion, shaft end held 40 µm away
    fr = extract_features(_recording({2: (x2, y2), 3: (x3, y3)}))
    assert fr["cpl_dc_offset_per_c"] == pytest.approx(40.0 / CLEARANCE_UM, rel=1e-9)
    assert fr["cpl_1x_rel_fwd_um_pp"] < 1e-9
    assert fr["cpl_ac_rel_rms_um"] < 1e-6
    assert fr["cpl_rel_rms_per_c"] == pytest.approx(0.2, rel=1e-6)


@pytest.mark.parametrize("forward", [True, False])
def test_ends_circling_each_other(forward):
    """b3 = b2 − δ e_r(±θ): a relative circle of radius δ; only the forward one is 1X forward."""
    delta = 30.0
    th = _theta()
    x2, y2 = _shaft(th)
    s = 1.0 if forward else -1.0
    x3, y3 = x2 - delta * np.cos(s * th + 0.7), y2 - delta * np.sin(s * th + 0.7)
    fr = extract_features(_recording({2: (x2, y2), 3: (x3, y3)}))
    assert fr["cpl_1x_rel_fwd_um_pp"] == pytest.approx(2 * delta if forward else 0.0, rel=1e-9, abs=1e-9)
    assert fr["cpl_1x_rel_fwd_pp_per_c"] == pytest.approx(fr["cpl_1x_rel_fwd_um_pp"] / CLEARANCE_UM, rel=1e-12)
    assert fr["cpl_ac_rel_rms_um"] == pytest.approx(delta, rel=1e-6)
    assert fr["cpl_dc_offset_per_c"] < 1e-9
    assert fr["cpl_rel_rms_per_c"] == pytest.approx(delta / CLEARANCE_UM, rel=1e-6)


def test_non_synchronous_relative_motion_counts_and_probe_noise_does_not():
    th = _theta()
    x2, y2 = _shaft(th)
    whirl = 0.43 * th
    rng = np.random.default_rng(3)
    sigma = 2.0
    noisy = {b: (x2 + (10.0 * np.cos(whirl) if b == 3 else 0.0) + rng.normal(0, sigma, N),
                 y2 + (10.0 * np.sin(whirl) if b == 3 else 0.0) + rng.normal(0, sigma, N)) for b in (2, 3)}
    fr = extract_features(_recording(noisy))
    # a 10 µm circle at 0.43X in r_b2 − r_b3 is 10 µm rms; the four probes' noise (2 µm each, 4 µm rms
    # in the difference) is taken out
    assert fr["cpl_ac_rel_rms_um"] == pytest.approx(10.0, abs=0.4)
    quiet = {b: (x2 + rng.normal(0, sigma, N), y2 + rng.normal(0, sigma, N)) for b in (2, 3)}
    assert extract_features(_recording(quiet))["cpl_ac_rel_rms_um"] < 0.6


def test_missing_inputs_give_nan_not_numbers():
    th = _theta()
    x2, y2 = _shaft(th)
    names = list(COUPLING_FEATURES)
    only_b2 = extract_features(_recording({2: (x2, y2), 4: (x2, y2)}))
    assert all(np.isnan(only_b2[n]) for n in names)
    no_c = extract_features(_recording({2: (x2, y2), 3: (x2 + 5.0, y2)}, clearance_um=None))
    assert np.isfinite(no_c["cpl_1x_rel_fwd_um_pp"]) and np.isfinite(no_c["cpl_ac_rel_rms_um"])
    assert all(np.isnan(no_c[n]) for n in names if n.endswith("_per_c"))
    raw_gap = extract_features(_recording({2: (x2 + 1500.0, y2), 3: (x2, y2)}))   # 7.5 c: a raw probe gap
    assert np.isnan(raw_gap["cpl_dc_offset_per_c"]) and np.isnan(raw_gap["cpl_rel_rms_per_c"])
    assert np.isfinite(raw_gap["cpl_ac_rel_rms_per_c"])


def test_evidence_reads_the_shaft_ends():
    th = _theta()
    x2, y2 = _shaft(th, mean=(0.0, -70.0))
    x3, y3 = x2 - 20.0 * np.cos(th), y2 + 30.0 - 20.0 * np.sin(th)
    items = {it.name: it for it in evidence(extract_features(_recording({2: (x2, y2), 3: (x3, y3)})))}
    static, moving = items["static offset across the coupling"], items["1X relative motion across the coupling"]
    assert static.number == pytest.approx(30.0 / CLEARANCE_UM, rel=1e-6) and "30 µm" in static.value
    assert moving.number == pytest.approx(40.0, rel=1e-6) and "40 µm pk-pk" in moving.value
    no_c = {it.name: it for it in evidence(extract_features(_recording({2: (x2, y2), 3: (x3, y3)},
                                                                       clearance_um=None)))}
    assert no_c["static offset across the coupling"].value == "not measurable"


@pytest.mark.parametrize("mechanism", ["pin", "rigid", "offset", "flexible"])
def test_simulated_offset_is_read_across_the_coupling(mechanism):
    """docs/model.md: pin keeps |r3 − r4| = δ, rigid carries δ round at 1X, offset displaces the exciter's bearings
    by δ with r3 = r4; a flexible coupling takes up part of the same offset in its own compliance."""
    delta, spr, revs = 0.2, 128, 48
    plant = simulator.Plant.default()
    res = simulator.simulate(plant, 1950.0, delta, 0.05, mechanism=mechanism, transient_revs=300, record_revs=revs,
                             samples_per_rev=spr)
    assert res.status == "ok"
    d_um = res.journal_displacements_m * 1e6
    rec = _recording({b + 1: (d_um[:, b, 0], d_um[:, b, 1]) for b in range(4)}, speed_rpm=1950.0,
                     clearance_um=plant.clearance_m * 1e6)
    rec = Recording(sample_rate_hz=spr * 1950.0 / 60.0, channels=rec.channels, speed_rpm=1950.0,
                    clearance_um=plant.clearance_m * 1e6)
    fr = extract_features(rec)
    if mechanism == "flexible":
        assert 0.4 * delta < fr["cpl_rel_rms_per_c"] < 1.7 * delta   # a rough share of δ (features._coupling)
    else:
        assert fr["cpl_rel_rms_per_c"] == pytest.approx(delta, abs=2e-3), mechanism
    if mechanism == "rigid":
        assert fr["cpl_1x_rel_fwd_pp_per_c"] == pytest.approx(2 * delta, abs=2e-3)
    if mechanism == "offset":
        assert fr["cpl_dc_offset_per_c"] == pytest.approx(delta, abs=1e-3)
