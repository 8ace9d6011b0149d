"""A 1X / 2X common to every probe: mains pickup on a grid-synchronous machine (features._common_mode, the sanity
checks ``common_mode_1x`` / ``common_mode_2x`` and the verdict's ``common_mode`` doubt)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotordiag.features import (
    ProbeChannel,
    Recording,
    common_mode,
    common_mode_share,
    extract_features,
    without_common_mode,
)
from tests.service_util import simulated_channels

SPEED_RPM = 1800.0
REGISTRY = Path(__file__).resolve().parent.parent / "models" / "default_registry"


def _recording(pickup_um: float = 0.0, order: int = 2, phase_rad: float = 0.0, delta: float = 0.0,
               bearings: tuple[int, ...] = (1, 2, 3, 4)) -> Recording:
    """The simulated default plant with ``pickup_um`` (0-pk) at ``order`` × the running frequency added to every
    channel, in phase: what a ground loop on a grid-synchronous generator adds."""
    fs, ch = simulated_channels(misalignment=delta, speed_rpm=SPEED_RPM)
    t = np.arange(len(ch[0][2])) / fs
    hum = pickup_um * np.cos(2 * np.pi * order * SPEED_RPM / 60.0 * t + phase_rad)
    return Recording(fs, [ProbeChannel(b, a, "um", d + hum) for b, a, d in ch if b in bearings],
                     speed_rpm=SPEED_RPM, clearance_um=350.0)


def _codes(fr) -> dict[str, str]:
    return {f.code: f.level for f in fr.sanity}


def test_share_is_one_for_one_common_signal_and_low_for_an_orbit():
    assert common_mode_share(np.full(8, 3.0 - 1.0j)) == pytest.approx(1.0)
    # the two probes of a circular forward orbit read it 90° apart: half the power is common, whatever the bearing
    circle = np.tile([1.0, -1.0j], 4)
    assert common_mode_share(circle) == pytest.approx(0.5)
    assert common_mode_share(np.array([1.0, -1.0, 1.0, -1.0])) == pytest.approx(0.0)
    assert np.isnan(common_mode_share(np.zeros(6)))


def test_the_clean_recording_has_no_common_mode_finding():
    fr = extract_features(_recording())
    assert not {"common_mode_1x", "common_mode_2x"} & set(_codes(fr))
    assert common_mode(fr, 2).share < 0.5


def test_a_2x_pickup_at_every_probe_is_found_and_says_what_to_check():
    fr = extract_features(_recording(pickup_um=12.0))
    assert _codes(fr).get("common_mode_2x") == "warn"
    values = next(f.values for f in fr.sanity if f.code == "common_mode_2x")
    cm = common_mode(fr, 2)
    assert values["bearings"] == "1, 2, 3, 4" and values["n_probes"] == cm.n_probes
    assert values["amp"].value_um == cm.amp_um_pp and values["share_pct"] == pytest.approx(100 * cm.share)
    assert cm.n_probes == 8 and cm.share > 0.9
    assert cm.amp_um_pp == pytest.approx(24.0, rel=0.25)      # the pickup dominates the 2X


def test_a_1x_pickup_at_every_probe_is_found():
    fr = extract_features(_recording(pickup_um=40.0, order=1))
    assert _codes(fr).get("common_mode_1x") == "warn"


def test_coupling_bearings_alone_are_not_judged():
    """With 4 probes a shaft's own 2X orbit can be nearly common (a linear orbit along the probes' bisector, in
    phase at both coupling-end journals): no judgement, however strong the pickup."""
    fr = extract_features(_recording(pickup_um=12.0, bearings=(2, 3)))
    assert common_mode(fr, 2) is None
    assert "common_mode_2x" not in _codes(fr)


def test_removing_the_common_signal_gives_back_the_recording_without_pickup():
    clean = extract_features(_recording())
    rec = _recording(pickup_um=8.0)
    fr = extract_features(rec)
    cm = common_mode(fr, 2)
    again = extract_features(without_common_mode(rec, fr, [cm]))
    before = np.array([det.probe_coeffs_um[:, 1] for det in fr.bearings.values()])
    after = np.array([det.probe_coeffs_um[:, 1] for det in again.bearings.values()])
    expected = np.array([det.probe_coeffs_um[:, 1] for det in clean.bearings.values()])
    # what is left is the shaft's own 2X less its own common part (the mean of the probes' 2X)
    assert after == pytest.approx(expected - expected.mean(), abs=1e-6 * np.abs(before).max())
    assert common_mode(again, 2).share < 1e-6


def test_shipped_model_reads_the_recording_without_its_pickup():
    """The healthy default plant with an 8 µm 2X pickup (below the sanity check's share of 0.85) and a 12 µm one
    (share 0.96: the 2X is the pickup). v0003 called them slight and moderate as sent; v0004, which reads the columns
    across bearings (the journals' load sharing), calls both aligned as sent. The pickup is removed before the
    verdict all the same: both are the plant's own class, aligned, uncertain, and the reason names what was removed
    and the class as sent (the 12 µm pickup's sanity finding is kept: it says what was sent). Without pickup there is no such reason and nothing is removed."""
    from rotordiag.models.pipeline import diagnose_recording, read_features
    from rotordiag.models.predict import load_bundle, ood_score_and_class

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    bundle = load_bundle(REGISTRY)

    def codes(v):
        return [r["code"] for r in v.reasons]

    plain, fr_plain = diagnose_recording(bundle, _recording())
    assert plain.model_severity == "aligned" and "common_mode" not in codes(plain)
    for pickup_um, as_sent in ((8.0, "aligned"), (12.0, "aligned")):
        rec = _recording(pickup_um=pickup_um, phase_rad=0.75 * np.pi)
        assert ood_score_and_class(bundle, read_features(rec))[1] == as_sent      # the pickup's class, as sent
        v, fr = diagnose_recording(bundle, rec)
        assert v.model_severity == "aligned" and v.status == "uncertain"
        assert codes(v)[0] == "common_mode"
        msg = next(r["message"] for r in v.reasons if r["code"] == "common_mode")
        assert msg.values["call"] == "aligned"
        assert msg.values.get("call_as_sent") == (None if as_sent == "aligned" else as_sent)   # named when it differs
        assert common_mode(fr, 2).share < 0.2                                 # the verdict's features: without it
        assert ("common_mode_2x" in _codes(fr)) == (pickup_um == 12.0)         # the sanity finding as sent, kept
        assert fr.warnings == read_features(rec).warnings


def test_a_synthetic_train_with_a_common_2x():
    """A synthetic train (forward circular 1X of 20 µm at each bearing, in its own phase; the 2X a 1 µm pickup
    alone): the 2X is all common, the 1X is not."""
    fs, n = 2048.0, 2048 * 2
    t = np.arange(n) / fs
    theta = 2 * np.pi * SPEED_RPM / 60.0 * t
    chans = []
    for b in (1, 2, 3, 4):
        lag = np.deg2rad(40.0 * b)
        for a in (45.0, 135.0):
            # a forward circle read by a probe at a: 20 cos(θ − lag − a)
            chans.append(ProbeChannel(b, a, "um", 20.0 * np.cos(theta - lag - np.deg2rad(a)) + 1.0 * np.cos(2 * theta)
                                      + 30.0))
    fr = extract_features(Recording(fs, chans, speed_rpm=SPEED_RPM, clearance_um=350.0))
    assert common_mode(fr, 2).share == pytest.approx(1.0, abs=1e-6)
    assert _codes(fr).get("common_mode_2x") == "warn"
    assert "common_mode_1x" not in _codes(fr)


def test_the_evidence_shows_a_notable_common_part_and_only_then():
    from rotordiag.features import evidence

    def items(fr):
        return [e for e in evidence(fr) if e.scope == "all probes"]

    assert items(extract_features(_recording())) == []
    weak = items(extract_features(_recording(pickup_um=6.0, phase_rad=0.75 * np.pi)))     # share 0.71
    assert [e.name for e in weak] == ["2X common to every probe"] and "likely" in weak[0].meaning
    assert weak[0].number == pytest.approx(0.71, abs=0.01)
    strong = items(extract_features(_recording(pickup_um=12.0)))                          # share 0.96
    assert "not shaft motion" in strong[0].meaning and strong[0].value.startswith("96 % of the 2X power")


def test_a_recording_read_by_take_is_not_cleaned_with_one_shaft_angle():
    """Two takes, each with its own keyphasor, and a 2X common to every probe: each take's phases refer to its own
    mark, so one shaft angle cannot subtract the signal from both — the pickup is not removed (the sanity warning
    stays), while the same recording in one take is cleaned."""
    from rotordiag.models.checks.common_mode import remove_pickup
    from rotordiag.models.pipeline import read_features

    one = _recording(pickup_um=12.0)
    fr_one = read_features(one)
    assert remove_pickup(one, fr_one, read_features) is not None
    period = 60.0 / SPEED_RPM
    t_end = (one.n_points - 1) / one.sample_rate_hz
    pulses = np.arange(0.3 * period, t_end, period)
    takes = Recording(one.sample_rate_hz, one.channels, clearance_um=350.0, acquisitions="1,2;3,4",
                      keyphasor_times_s=[pulses, pulses])
    fr_takes = read_features(takes)
    assert takes.keyphasor_takes is not None and common_mode(fr_takes, 2).share > 0.6
    assert remove_pickup(takes, fr_takes, read_features) is None
