"""The shooting start of dataset samples and sweep points (issue 16 item 4).

A sample started on the shot period-1 orbit must carry the same labels and the same
features (``rotordiag.features.extract_features`` of its probe waveforms) as the
brute-force sample (400 transient revolutions), and a sample where shooting is not
safe must fall back to integration and say so.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from rotordiag.features import FEATURE_NAMES, ProbeChannel, Recording, extract_features
from rotordiag.simulator import Plant, build_system
from rotordiag.simulator.dataset.design import build_design
from rotordiag.simulator.dataset.measurement import MeasurementSettings
from rotordiag.simulator.dataset.spec import load_spec
from rotordiag.simulator.dataset.worker import SampleTask, SimulationSettings, run_sample
from rotordiag.simulator.steady.start import steady_start

SPEC = Path(__file__).resolve().parent / "reference" / "steady_start_spec.toml"
#: waveform agreement, µm: the two starts differ by the integrator's error (~1e-7 of the state);
#: float32 storage of ~300 µm values rounds at ~3e-5 µm
WAVE_TOL_UM = 1e-3
#: feature agreement (absolute, on top of a relative 1e-5)
FEATURE_ATOL = 1e-5


def _features(out, meas: MeasurementSettings, speed_rpm: float, clearance_m: float) -> np.ndarray:
    rec = Recording(sample_rate_hz=meas.sample_rate_hz,
                    channels=[ProbeChannel(bearing=b, angle_deg=a, units="um", data=out.waveforms_um[c])
                              for c, (b, a) in enumerate(meas.channels)],
                    speed_rpm=speed_rpm, clearance_um=clearance_m * 1e6)
    return extract_features(rec).values


@pytest.fixture(scope="module")
def shipped():
    resolved = load_spec(SPEC)
    sim = dataclasses.replace(SimulationSettings.from_spec(resolved.spec), classify_motion=True)
    return build_design(resolved), MeasurementSettings.from_spec(resolved.spec), sim


# samples of the first shipped default-model spec (a frozen copy): period-1 pin and rigid at 1330-2210 r/min (shooting),
# and rigid at 2764 r/min, whose orbit has max |μ| ≈ 0.994 (> 0.99: integration)
@pytest.mark.parametrize("index, expected_path", [(21, "shooting"), (1, "shooting"), (12, "shooting"),
                                                  (18, "shooting"), (15, "integrate")])
def test_shooting_start_gives_the_brute_force_labels_and_features(shipped, index, expected_path):
    design, meas, sim = shipped
    p = design[index]
    outs = {m: run_sample(SampleTask(p, dataclasses.replace(sim, steady_start=m), meas))
            for m in ("integrate", "shooting")}
    brute, shot = outs["integrate"], outs["shooting"]
    assert brute.steady_start == "integrate" and brute.steady_note == ""
    assert shot.steady_start == expected_path, shot.steady_note
    if expected_path == "integrate":
        assert shot.steady_note  # says why
    assert shot.status == brute.status == "ok"
    assert (shot.motion_kind, shot.motion_period) == (brute.motion_kind, brute.motion_period)
    assert shot.simulated_mechanism == brute.simulated_mechanism and shot.record_revs == brute.record_revs
    np.testing.assert_allclose(shot.waveforms_um, brute.waveforms_um, rtol=0, atol=WAVE_TOL_UM)
    clearance = p.plant["clearance_m"]
    fa = _features(brute, meas, p.speed_rpm, clearance)
    fb = _features(shot, meas, p.speed_rpm, clearance)
    assert fa.shape == (len(FEATURE_NAMES),)
    np.testing.assert_allclose(fb, fa, rtol=1e-5, atol=FEATURE_ATOL)
    if expected_path == "shooting":  # and it was worth it: far fewer right-hand-side evaluations
        assert shot.nfev < 0.6 * brute.nfev


def test_fallback_when_the_warm_up_does_not_approach_a_stable_period_one_orbit():
    """Above the whirl threshold (aligned, 2450 r/min) the period-1 orbit is unstable: integrate."""
    plant = Plant.default()
    system = build_system(plant, 2450.0, 0.0, 0.05, mechanism="aligned")
    st = steady_start(system, 400)
    assert st.path == "integrate" and st.note
    assert st.transient_revs == 400 - st.warmup_revs and st.warmup_revs > 0
    assert steady_start(system, 400, "integrate").transient_revs == 400
    with pytest.raises(ValueError, match="steady_start"):
        steady_start(system, 400, "newton")


def test_shooting_start_is_the_period_one_orbit():
    plant = Plant.default()
    system = build_system(plant, 1950.0, 0.02, 0.05, mechanism="pin")
    st = steady_start(system, 400)
    assert st.path == "shooting" and st.transient_revs == 0 and st.max_multiplier < 0.99
    from rotordiag.simulator.steady import RotorMap

    pmap = RotorMap(system)
    x = pmap.reduce(st.state)
    assert np.max(np.abs(pmap.difference(pmap.evaluate(x, 1).value, x))) < 1e-8
