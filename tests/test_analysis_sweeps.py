"""Rotor sweeps, rotor LLE and the analysis CLI (short runs on the default plant)."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.simulator import Plant, simulate
from rotordiag.simulator.analysis.sweeps import SweepResult, misalignment_sweep, rotor_lyapunov, speed_sweep
from rotordiag.simulator.simulate import order_amplitudes

PLANT = Plant.default()
SHORT = dict(transient_revs=200, record_revs=32, progress=False)


def test_low_speed_sweep_is_period_one_with_negative_lle():
    sw = speed_sweep(PLANT, [1200, 1500, 1800], 0.02, 0.05, n_workers=0, lle_revs=40, **SHORT)
    assert list(sw.status) == ["ok"] * 3
    assert list(sw.motion) == ["period-1"] * 3
    assert np.all(sw.period == 1)
    # a stable synchronous orbit contracts: LLE clearly below the noise level
    assert np.all(sw.lle_per_rev < -0.03)
    np.testing.assert_allclose(sw.lle_per_s, sw.lle_per_rev * sw.speed_rpm / 60.0)


def test_sweep_points_equal_direct_simulation():
    """steady_start="integrate" is the brute-force run bit for bit; the shooting start equals it to 1e-7."""
    res = simulate(PLANT, 1600.0, 0.1, 0.05, transient_revs=200, record_revs=32, samples_per_rev=64)
    c = PLANT.clearance_m
    sw = speed_sweep(PLANT, [1600.0], 0.1, 0.05, n_workers=0, samples_per_rev=64, steady_start="integrate", **SHORT)
    assert list(sw.steady_start) == ["integrate"]
    np.testing.assert_array_equal(sw.poincare[0], res.poincare_m[:, 2, 0] / c)
    np.testing.assert_array_equal(sw.orders[0], order_amplitudes(res)[1, 0] / c)
    assert sw.pkpk[0] == pytest.approx(np.ptp(res.positions_m[:, 2, 0]) / c)
    shot = speed_sweep(PLANT, [1600.0], 0.1, 0.05, n_workers=0, samples_per_rev=64, **SHORT)
    assert list(shot.steady_start) == ["shooting"]  # the default, and it converges here (period 1)
    np.testing.assert_allclose(shot.poincare[0], res.poincare_m[:, 2, 0] / c, rtol=0, atol=1e-7)
    np.testing.assert_allclose(shot.orders[0], order_amplitudes(res)[1, 0] / c, rtol=0, atol=1e-7)
    assert shot.motion[0] == sw.motion[0] == "period-1"


def test_misalignment_sweep_shape_and_determinism():
    deltas = [0.0, 0.1, 0.4]
    a = misalignment_sweep(PLANT, 1843, deltas, 0.05, n_workers=0, **SHORT)
    b = misalignment_sweep(PLANT, 1843, deltas, 0.05, n_workers=0, **SHORT)
    assert a.parameter == "misalignment"
    assert a.poincare.shape == (3, 32)
    assert a.sections.shape == (3, 32, 6, 2)
    assert a.orders.shape == (3, 3)
    np.testing.assert_array_equal(a.values, deltas)
    np.testing.assert_array_equal(a.speed_rpm, [1843.0] * 3)
    for name in SweepResult._ARRAYS:
        np.testing.assert_array_equal(getattr(a, name) if name != "wall_time_s" else 0,
                                      getattr(b, name) if name != "wall_time_s" else 0)


def test_dask_runner_gives_the_same_sweep_as_in_process():
    speeds = [1300.0, 1700.0]
    serial = speed_sweep(PLANT, speeds, 0.1, 0.05, n_workers=0, **SHORT)
    dask = speed_sweep(PLANT, speeds, 0.1, 0.05, n_workers=2, **SHORT)
    np.testing.assert_array_equal(serial.sections, dask.sections)
    np.testing.assert_array_equal(serial.motion, dask.motion)


def test_hdf5_round_trip(tmp_path):
    sw = speed_sweep(PLANT, [1400.0, 1900.0], 0.02, 0.05, n_workers=0, lle_revs=12, **SHORT)
    path = tmp_path / "sweep.h5"
    sw.to_hdf5(path)
    back = SweepResult.from_hdf5(path)
    assert back.parameter == "speed_rpm"
    assert back.inputs == sw.inputs
    for name in SweepResult._ARRAYS:
        np.testing.assert_array_equal(getattr(back, name), getattr(sw, name))


def test_aligned_lle_leaves_out_the_coupling_angle():
    """Δ = 0 runs 'aligned', where φ is not dynamic: perturbing it would freeze the LLE at 0."""
    res = simulate(PLANT, 1500.0, 0.0, 0.05, transient_revs=200, record_revs=8)
    lle = rotor_lyapunov(PLANT, 1500.0, 0.0, 0.05, n_revs=40, transient_revs=0, initial_state=res.final_state)
    assert lle.lle_per_interval < -0.05
    assert lle.lle_per_s == pytest.approx(lle.lle_per_interval * 1500.0 / 60.0)


@pytest.mark.parametrize("kwargs, word", [
    (dict(node=7), "node"),
    (dict(direction="z"), "direction"),
    (dict(lle_revs=-1), "lle_revs"),
    (dict(record_revs=4), "record_revs"),
    (dict(mechanism="glue"), "mechanism"),
])
def test_bad_sweep_arguments(kwargs, word):
    with pytest.raises(ValueError, match=word):
        speed_sweep(PLANT, [1500.0], 0.1, 0.05, n_workers=0, progress=False, **kwargs)


def test_bad_sweep_values():
    with pytest.raises(ValueError, match="speeds_rpm"):
        speed_sweep(PLANT, [50.0], 0.1, 0.05, n_workers=0, progress=False)
    with pytest.raises(ValueError, match="misalignments"):
        misalignment_sweep(PLANT, 1500, [0.1, 1.5], 0.05, n_workers=0, progress=False)
    with pytest.raises(ValueError, match="unbalance"):
        speed_sweep(PLANT, [1500.0], 0.1, 0.9, n_workers=0, progress=False)


def test_amplitude_speed_curves_match_individual_sweeps():
    from rotordiag.simulator.analysis import amplitude_speed_curves

    curves = amplitude_speed_curves(PLANT, [1300.0, 1700.0], [0.0, 0.2], 0.05, n_workers=0, **SHORT)
    assert sorted(curves) == [0.0, 0.2]
    single = speed_sweep(PLANT, [1300.0, 1700.0], 0.2, 0.05, n_workers=0, **SHORT)
    np.testing.assert_array_equal(curves[0.2].pkpk, single.pkpk)
    np.testing.assert_array_equal(curves[0.2].orders, single.orders)
    assert np.all(curves[0.0].misalignment == 0.0)
    # 1X dominates at these speeds and peak-to-peak exceeds twice the 1X amplitude minus the rest
    for sw in curves.values():
        assert np.all(sw.orders[:, 0] > sw.orders[:, 2])
        assert np.all(sw.pkpk >= 2 * (sw.orders[:, 0] - sw.orders[:, 1] - sw.orders[:, 2]))
