"""Inputs, outputs and failure modes of the simulator's public API."""
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.simulator import Plant, build_system, simulate


@pytest.mark.parametrize("kwargs, name", [
    (dict(speed_rpm=0.0), "speed_rpm"), (dict(speed_rpm=-100.0), "speed_rpm"), (dict(speed_rpm=7000.0), "speed_rpm"),
    (dict(speed_rpm=float("nan")), "speed_rpm"), (dict(misalignment=-0.1), "misalignment"),
    (dict(misalignment=0.95), "misalignment"), (dict(unbalance=0.6), "unbalance"),
    (dict(unbalance=float("inf")), "unbalance"), (dict(mechanism="welded"), "mechanism"),
    (dict(rtol=0.5), "rtol"), (dict(record_revs=0), "record_revs"), (dict(samples_per_rev=2), "samples_per_rev"),
    (dict(exciter_unbalance=-1.0), "exciter_unbalance"), (dict(offset_angle_rad=float("nan")), "offset_angle_rad"),
    (dict(initial_state=np.zeros(5)), "initial_state"), (dict(sample_rate_hz=10.0), "sample_rate_hz"),
])
def test_bad_input_names_the_parameter(kwargs, name):
    args = dict(plant=Plant.default(), speed_rpm=1950.0, misalignment=0.1, unbalance=0.05, transient_revs=1,
                record_revs=1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        simulate(**args)


@pytest.mark.parametrize("field, value", [("generator_mass_kg", 0.0), ("clearance_m", -1e-4), ("asymmetry", 0.5),
                                          ("viscosity_pa_s", float("nan")), ("exciter_damping_n_s_m", -1.0),
                                          ("bearing_radius_m", (0.2, 0.2, 0.1)), ("bearing_model", "long"),
                                          ("bearing_offset_m", ((4e-4, 0), (0, 0), (0, 0), (0, 0)))])
def test_nonphysical_plant_rejected(field, value):
    with pytest.raises(ValueError, match=field):
        Plant.default().replace(**{field: value})


def test_plant_is_immutable_and_round_trips(tmp_path):
    plant = Plant.default().replace(asymmetry=0.03, bearing_offset_m=((0, 1e-5), (0, 0), (0, 0), (2e-5, 0)))
    with pytest.raises(AttributeError):
        plant.asymmetry = 0.1  # type: ignore[misc]
    for suffix in (".toml", ".json"):
        path = tmp_path / f"plant{suffix}"
        plant.to_file(path)
        assert Plant.from_file(path) == plant
    assert Plant.from_dict(json.loads(json.dumps(plant.to_dict()))) == plant
    assert plant.plant_id() != Plant.default().plant_id()
    (tmp_path / "bad.toml").write_text("asymmetry = 0.01\nrotor_mass = 3\n")
    with pytest.raises(ValueError, match="rotor_mass"):
        Plant.from_file(tmp_path / "bad.toml")
    (tmp_path / "broken.json").write_text("{")
    with pytest.raises(ValueError, match="not valid JSON"):
        Plant.from_file(tmp_path / "broken.json")


def test_result_shapes_and_conventions():
    res = simulate(Plant.default(), 1950.0, 0.1, 0.05, transient_revs=20, record_revs=3, samples_per_rev=16)
    assert res.status == "ok"
    assert res.time_s.shape == (48,) and res.positions_m.shape == (48, 6, 2)
    assert res.phi_rad.shape == (48,) and np.isfinite(res.phi_rad).all()
    assert res.poincare_m.shape == (3, 6, 2)
    # samples at exact phases: t·Ω = 2π(20 + k/16); Poincaré points are every 16th sample
    np.testing.assert_allclose(res.time_s * 1950 * math.pi / 30, 2 * math.pi * (20 + np.arange(48) / 16), rtol=1e-13)
    np.testing.assert_allclose(res.poincare_m, res.positions_m[::16], rtol=0, atol=1e-15)
    # |r3 − r4| = δ for the pin
    link = np.hypot(*(res.positions_m[:, 2] - res.positions_m[:, 3]).T)
    np.testing.assert_allclose(link, 0.1 * 0.35e-3, rtol=1e-12)
    aligned = simulate(Plant.default(), 1950.0, 0.0, 0.05, transient_revs=2, record_revs=1, samples_per_rev=8)
    assert np.isnan(aligned.phi_rad).all() and aligned.inputs["mechanism"] == "aligned"


def test_fixed_sample_rate_and_continuation():
    res = simulate(Plant.default(), 1800.0, 0.1, 0.05, transient_revs=10, record_revs=4, sample_rate_hz=2000.0)
    assert np.allclose(np.diff(res.time_s), 1 / 2000.0)
    assert len(res.time_s) == int(4 / 30 * 2000)
    # continuing from final_state = one longer run
    a = simulate(Plant.default(), 1950.0, 0.1, 0.05, transient_revs=10, record_revs=2, samples_per_rev=8)
    b = simulate(Plant.default(), 1950.0, 0.1, 0.05, transient_revs=0, record_revs=2, samples_per_rev=8,
                 initial_state=a.final_state, rtol=1e-6)
    long = simulate(Plant.default(), 1950.0, 0.1, 0.05, transient_revs=12, record_revs=2, samples_per_rev=8)
    assert np.abs(b.positions_m - long.positions_m).max() < 1e-3 * 0.35e-3


def test_flow_map_advance_matches_simulate():
    system = build_system(Plant.default(), 1950.0, 0.1, 0.05)
    y, status = system.advance(system.initial_state(), 0.0, 5)
    res = simulate(Plant.default(), 1950.0, 0.1, 0.05, transient_revs=0, record_revs=6, samples_per_rev=4)
    assert status == "ok"
    np.testing.assert_allclose(system.node_positions(0.0, y)[0], res.poincare_m[5], rtol=1e-5, atol=1e-12)


def test_contact_returns_samples_so_far_with_status():
    # linear bearings too soft for the rotor's weight: the journal sags onto its bushing
    plant = Plant.default().replace(bearing_model="linear", linear_bearing_stiffness_n_m=2e8,
                                    linear_bearing_damping_n_s_m=1e5)
    res = simulate(plant, 1950.0, 0.1, 0.05, transient_revs=0, record_revs=20)
    assert res.status == "contact" and "bushing" in res.message
    assert 0 < len(res.time_s) < 20 * 128
    assert np.isfinite(res.positions_m).all()


def test_numba_cache_means_no_recompile_in_a_second_process():
    code = ("from simulator import Plant, simulate; from simulator import _kernels as K;"
            "simulate(Plant.default(), 1950., 0.1, 0.05, transient_revs=1, record_revs=1);"
            "print(sum(K.integrate.stats.cache_hits.values()), sum(K.integrate.stats.cache_misses.values()))")
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)  # make sure the cache exists
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout.split()
    assert int(out[0]) >= 1 and int(out[1]) == 0


def test_cli_simulate_and_modal(tmp_path):
    runner = CliRunner()
    png, h5 = tmp_path / "o.png", tmp_path / "o.h5"
    r = runner.invoke(app, ["simulate", "--speed-rpm", "1950", "--misalignment", "0.1", "--transient-revs", "50",
                            "--record-revs", "8", "--json", "--plot", str(png), "--out", str(h5)])
    assert r.exit_code == 0, r.output
    summary = json.loads(r.stdout[r.stdout.index("{"):])
    assert summary["status"] == "ok" and len(summary["bearings"]) == 4
    assert summary["bearings"][0]["x_1x_um_0pk"] > 0
    assert png.stat().st_size > 10_000
    import h5py
    with h5py.File(h5) as f:
        assert f["positions_m"].shape == (8 * 128, 6, 2)
    r = runner.invoke(app, ["simulate", "--speed-rpm", "0", "--misalignment", "0.1"])
    assert r.exit_code == 2 and "speed_rpm must be in" in r.output
    r = runner.invoke(app, ["modal", "--speed-rpm", "1950"])
    assert r.exit_code == 0 and "18.4" in r.output
