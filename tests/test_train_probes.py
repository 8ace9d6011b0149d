"""A simulated train's probes in the recording layout: through ``features.extract_features``, whose 1X at every
probe must equal the train's frequency (unbalance) response there; bad channels refused."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording, extract_features
from rotordiag.simulator.train import TrainError, assemble, unbalance_response
from rotordiag.simulator.train.dynamics import simulate_train
from rotordiag.simulator.train.probes import train_probes

from .bench_util import bench_machine, ross_reference


@pytest.fixture(scope="module")
def run_and_asm():
    asm = assemble(ross_reference().reference_train(True))  # linear bearings: the frequency response is exact
    run = simulate_train(asm, 3000.0, transient_revs=60, record_revs=16, samples_per_rev=64, n_modes=16)
    assert run.ok
    return run, asm


def test_train_recording_goes_through_extract_features_with_the_frequency_responses_1x(run_and_asm):
    run, asm = run_and_asm
    angles = (30.0, 120.0)  # not the default pair: the projection is exercised
    probes = train_probes(run, [(b, a) for b in (1, 2, 3, 4) for a in angles])
    rec = Recording(sample_rate_hz=probes.sample_rate_hz,
                    channels=[ProbeChannel(b, a, "um", probes.waveforms_um[k]) for k, (b, a) in
                              enumerate(probes.channels)],
                    keyphasor_times_s=probes.keyphasor_times_s, clearance_um=probes.clearance_um)
    res = extract_features(rec)
    assert res.speed_source == "keyphasor" and res.speed_rpm == pytest.approx(3000.0, rel=1e-6)
    R = unbalance_response(asm, [3000.0])[0, asm.support_nodes, :] * 1e6  # (4, 2) complex, x = Re(R e^{iΩt})
    for b in (1, 2, 3, 4):
        det = res.bearings[b]
        for k, a in enumerate(angles):
            expect = R[b - 1, 0] * math.cos(math.radians(a)) + R[b - 1, 1] * math.sin(math.radians(a))
            got = det.probe_coeffs_um[k, 0]
            assert abs(got) == pytest.approx(abs(expect), rel=5e-3)
            assert abs(np.angle(got / expect)) < math.radians(0.5)
        # linear bearings, symmetric shafts, no 2X source: the 2X the features find is numerical noise
        assert np.abs(det.probe_coeffs_um[:, 1]).max() < 1e-3 * np.abs(det.probe_coeffs_um[:, 0]).max()


def test_probe_channels_are_checked(run_and_asm):
    run, _ = run_and_asm
    with pytest.raises(TrainError, match="bearings 1…4"):
        train_probes(run, [(5, 45.0)])
    with pytest.raises(TrainError, match="finite"):
        train_probes(run, [(1, float("nan"))])
    with pytest.raises(TrainError, match="bearing number, angle_deg"):
        train_probes(run, ["x"])
    default = train_probes(run)
    assert default.channels == tuple((b, a) for b in (1, 2, 3, 4) for a in (45.0, 135.0))



def test_probes_keep_the_static_journal_position():
    """Plain bearings under gravity: each probe's mean is its journal's mean position projected on the probe
    (x cos α + y sin α at 45° and 135°), the DC a DC-coupled probe keeps."""
    run = simulate_train(bench_machine(), 3000.0, transient_revs=2, record_revs=1, samples_per_rev=16)
    p = train_probes(run)
    x, y = run.journal_m.mean(axis=0).T * 1e6  # (n_bearings,) µm
    assert (np.hypot(x, y) > 0.02 * run.clearance_m * 1e6).all()  # every journal sits off its bearing centre
    np.testing.assert_allclose(p.waveforms_um[0::2].mean(axis=1), (x + y) / math.sqrt(2), rtol=1e-9)
    np.testing.assert_allclose(p.waveforms_um[1::2].mean(axis=1), (-x + y) / math.sqrt(2), rtol=1e-9)
