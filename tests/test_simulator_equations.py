"""Equations of motion against independent references (MODEL.md verification 1, 2, 5)."""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rotordiag.simulator import Plant, build_system, simulate
from rotordiag.simulator import _kernels as K
from tests.reference.rotor_numpy import ReferenceRotor, capone_literal, ocvirk_static


@pytest.mark.parametrize("eps, f_expected, psi_deg", [(0.1, 0.32153, 82.708), (0.5, 3.00152, 53.680),
                                                      (0.9, 96.0246, 20.826)])
@pytest.mark.parametrize("theta", [-1.2, 0.4, 2.5])
def test_capone_static_equals_ocvirk(eps, f_expected, psi_deg, theta):
    X, Y = eps * math.cos(theta), eps * math.sin(theta)
    fx, fy = K.capone_force(X, Y, 0.0, 0.0)
    f_ocv, psi = ocvirk_static(eps)
    assert math.hypot(fx, fy) == pytest.approx(f_ocv, rel=1e-9)
    assert f_ocv == pytest.approx(f_expected, rel=2e-5)  # MODEL.md's printed figures
    assert math.degrees(psi) == pytest.approx(psi_deg, abs=1e-3)
    # attitude angle: between the load (−f) and the line of centres (journal position);
    # the journal lags the load in the direction of rotation (counter-clockwise shaft)
    load_angle = math.atan2(-fy, -fx)
    lag = (theta - load_angle) % (2 * math.pi)
    assert lag == pytest.approx(psi, abs=1e-9)


def test_downward_load_settles_down_and_right():
    eps = 0.3
    ang = ocvirk_static(eps)[1] - math.pi / 2  # load straight down, journal lags by ψ
    assert math.degrees(ang) == pytest.approx(-21.8, abs=0.05)  # MODEL.md's figure
    fx, fy = K.capone_force(eps * math.cos(ang), eps * math.sin(ang), 0.0, 0.0)
    assert fy > 0 and abs(fx) < 1e-9 * fy  # the film pushes straight up: equilibrium under gravity


def test_capone_matches_literal_formula_and_guards_domain():
    rng = np.random.default_rng(1)
    for _ in range(200):
        r, th = rng.uniform(0, 0.95), rng.uniform(-np.pi, np.pi)
        X, Y = r * math.cos(th), r * math.sin(th)
        Xd, Yd = rng.normal(scale=0.3, size=2)
        np.testing.assert_allclose(K.capone_force(X, Y, Xd, Yd), capone_literal(X, Y, Xd, Yd), rtol=1e-10, atol=1e-12)
    assert all(math.isnan(v) for v in K.capone_force(0.8, 0.7, 0.0, 0.0))  # outside the bushing
    assert K.capone_force(0.0, 0.0, 0.0, 0.0) == (0.0, 0.0)  # n = 0: no 0/0


def _random_state(rng, mech):
    y = np.zeros(K.N_STATE)
    y[:10] = rng.uniform(-0.5, 0.5, 10) * 0.6
    y[11:21] = rng.normal(scale=0.2, size=10)
    y[10] = rng.uniform(-np.pi, np.pi) if mech == "pin" else 0.0
    y[21] = rng.normal() if mech == "pin" else (1.0 if mech == "rigid" else 0.0)
    return y


@pytest.mark.parametrize("mechanism, delta", [("pin", 0.1), ("pin", 0.45), ("rigid", 0.2), ("aligned", 0.0)])
def test_rhs_matches_independent_numpy_reference(mechanism, delta):
    rng = np.random.default_rng(7)
    plant = Plant.default().replace(asymmetry=0.08, stiff_axis_angle_rad=0.3,
                                    bearing_offset_m=((1e-5, -2e-5), (0, 0), (3e-5, 1e-5), (0, -4e-5)))
    kw = dict(unbalance_phase_rad=0.4, exciter_unbalance=0.03, exciter_unbalance_phase_rad=1.1, offset_angle_rad=0.7)
    sys_ = build_system(plant, 2140.0, delta, 0.07, mechanism=mechanism, **kw)
    ref = ReferenceRotor(plant.to_dict(), 2140.0, delta, 0.07, mechanism, 0.4, 0.03, 1.1, 0.7)
    for _ in range(25):
        y = _random_state(rng, mechanism)
        tau = rng.uniform(0, 50)
        got = sys_.rhs(tau, y)
        want = ref.accel_to_nondim(ref(tau / ref.w, ref.to_si(y)))
        if mechanism != "pin":
            got, want = got[:21], want[:21]
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10 * np.abs(want).max())


@pytest.mark.parametrize("mechanism", ["pin", "rigid"])
def test_short_run_agrees_with_solve_ivp_dop853(mechanism):
    plant = Plant.default()
    revs = 3
    res = simulate(plant, 1950.0, 0.1, 0.05, mechanism=mechanism, transient_revs=0, record_revs=revs,
                   samples_per_rev=16, rtol=1e-10, atol=1e-12, record_state=True)
    ref = ReferenceRotor(plant.to_dict(), 1950.0, 0.1, 0.05, mechanism)
    y0 = build_system(plant, 1950.0, 0.1, 0.05, mechanism=mechanism).initial_state()
    t_eval = res.time_s
    sol = solve_ivp(ref, (0.0, t_eval[-1]), ref.to_si(y0), method="DOP853", rtol=1e-10, atol=1e-14,
                    t_eval=t_eval)
    assert sol.success
    x_ref = sol.y[:10].T  # SI positions of nodes 1, 2, 4, 5, 6
    x_sim = res.positions_m[:, [0, 1, 3, 4, 5], :].reshape(len(t_eval), 10)
    scale = np.abs(x_ref).max()
    err = np.abs(x_sim - x_ref).max() / scale
    assert err < 1e-7, err
