"""A train with six bearings (three rotors) through every recording reader and the features (issue 42 item 2): the
probe numbering goes beyond the paper model's four bearings; the 1X at bearings 5 and 6 is the train's frequency
response there; bearings 1–4's feature vector is the same with or without bearings 5 and 6 recorded."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from rotordiag.features import FEATURE_NAMES, ProbeChannel, Recording, extract_features
from rotordiag.features.reader import ReadOptions, read_recording
from rotordiag.simulator.cli import write_probes
from rotordiag.simulator.train import (
    Coupling,
    Disk,
    Rotor,
    Support,
    Train,
    Unbalance,
    assemble,
    unbalance_response,
    uniform_elements,
)
from rotordiag.simulator.train.dynamics import simulate_train
from rotordiag.simulator.train.probes import train_probes
from rotordiag.simulator.transient import keyphasor_pulse_signal

from .train_support import iso, two_rotor_train

SPEED_RPM = 3000.0


def _three_rotor_train() -> Train:
    """The tests' generator–exciter train with a third rotor (2.5 m, Ø 0.18 m, its own two bearings B5, B6, an
    unbalance of its own) coupled rigidly behind the exciter; linear bearings, so the frequency response is exact."""
    t = two_rotor_train(iso(2e9, 2e5), iso(5e8, 5e4), unbalance_kg_m=0.05)
    third = Rotor("pilot exciter", uniform_elements(2.5, 0.18, 6), disks=(Disk(3, 150.0, 5.0, 3.0),),
                  supports=(Support(1, iso(3e8, 3e5), name="B5"), Support(5, iso(3e8, 3e5), name="B6")),
                  unbalances=(Unbalance(3, 0.02, 1.0),))
    return Train((*t.rotors, third), (*t.couplings, Coupling("rigid")))


@pytest.fixture(scope="module")
def six():
    asm = assemble(_three_rotor_train())
    run = simulate_train(asm, SPEED_RPM, transient_revs=100, record_revs=16, samples_per_rev=64, n_modes=24)
    assert run.ok and run.journal_m.shape[1] == 6
    return run, asm, train_probes(run)


@pytest.fixture(scope="module")
def extracted(six):
    _, _, p = six
    rec = Recording(sample_rate_hz=p.sample_rate_hz,
                    channels=[ProbeChannel(b, a, "um", p.waveforms_um[k]) for k, (b, a) in enumerate(p.channels)],
                    keyphasor_times_s=p.keyphasor_times_s, clearance_um=p.clearance_um)
    return rec, extract_features(rec)


def test_bearings_5_and_6_have_the_trains_frequency_response_as_their_1x(six, extracted):
    _, asm, p = six
    assert p.channels == tuple((b, a) for b in range(1, 7) for a in (45.0, 135.0))
    _, res = extracted
    assert sorted(res.bearings) == [1, 2, 3, 4, 5, 6]
    R = unbalance_response(asm, [SPEED_RPM])[0, asm.support_nodes, :] * 1e6   # (6, 2), x = Re(R e^{iΩt})
    for b in (5, 6):
        det = res.bearings[b]
        for k, a in enumerate((45.0, 135.0)):
            expect = R[b - 1, 0] * math.cos(math.radians(a)) + R[b - 1, 1] * math.sin(math.radians(a))
            assert abs(det.probe_coeffs_um[k, 0]) == pytest.approx(abs(expect), rel=5e-3)
            assert abs(np.angle(det.probe_coeffs_um[k, 0] / expect)) < math.radians(0.5)
        assert det.features and all(n.startswith(f"b{b}_") for n in det.features)
        assert not any(n.startswith(f"b{b}_") for n in FEATURE_NAMES)            # not in the model's vector
    assert abs(R[4]).max() > 0.1 * abs(R[:4]).max()    # the third rotor moves: the check above is not of noise


def test_the_vector_of_bearings_1_to_4_does_not_change_with_bearings_5_and_6(extracted):
    rec, res = extracted
    four = replace(rec, channels=[c for c in rec.channels if c.bearing <= 4],
                   clearance_um={b: c for b, c in rec.clearance_um.items() if b <= 4})
    res4 = extract_features(four)
    assert len(res.values) == len(res4.values) == len(FEATURE_NAMES)
    np.testing.assert_array_equal(np.isnan(res.values), np.isnan(res4.values))
    ok = ~np.isnan(res.values)
    # the motion-type features see every bearing's Poincaré points; everything per bearing is identical
    per_bearing = np.array([n[:3] in {"b1_", "b2_", "b3_", "b4_"} for n in FEATURE_NAMES])
    np.testing.assert_allclose(res.values[ok & per_bearing], res4.values[ok & per_bearing], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("suffix", [".csv", ".npy", ".h5", ".uff"])
def test_every_reader_reads_the_six_bearings(six, tmp_path, suffix):
    run, _, p = six
    t = np.arange(p.waveforms_um.shape[1]) / p.sample_rate_hz
    path = tmp_path / f"six{suffix}"
    write_probes(path, p.waveforms_um, p.channels, p.sample_rate_hz, speed_rpm=SPEED_RPM,
                 clearance_um=min(p.clearance_um.values()),
                 keyphasor_signal=keyphasor_pulse_signal(t, p.sample_rate_hz, p.keyphasor_times_s))
    options = {".csv": ReadOptions(keyphasor_channel="kp"),
               ".npy": ReadOptions(sample_rate_hz=p.sample_rate_hz, keyphasor_channel=12,
                                   channels=",".join(f"{b}@{a:g}" for b, a in p.channels)),
               ".h5": ReadOptions(keyphasor_channel=12),
               ".uff": ReadOptions(keyphasor_channel="kp")}[suffix]
    rec = read_recording(path, options=options).recording
    got = {(c.bearing, c.angle_deg): c.data_um for c in rec.channels}
    assert sorted(got) == sorted(p.channels)
    atol = 6e-4 if suffix == ".csv" else 1e-3 * np.abs(p.waveforms_um).max()   # CSV: 3 decimals; float32 else
    for k, ch in enumerate(p.channels):
        np.testing.assert_allclose(got[ch], p.waveforms_um[k], atol=atol)
    res = extract_features(rec)
    assert sorted(res.bearings) == [1, 2, 3, 4, 5, 6] and res.speed_rpm == pytest.approx(SPEED_RPM, rel=1e-3)


def test_a_bearing_number_beyond_the_limit_says_so():
    with pytest.raises(ValueError, match="bearing number 1–8"):
        ProbeChannel(9, 45.0, "um", np.zeros(64))
    with pytest.raises(ValueError, match="1–8"):
        Recording(sample_rate_hz=1000.0, channels=[ProbeChannel(5, 45.0, "um", np.zeros(64)),
                                                   ProbeChannel(5, 135.0, "um", np.zeros(64))],
                  clearance_um={9: 300.0})
