"""Operation beyond the train's linear stability threshold (oil whip): the warning, and a time response whose
limit cycle converges as the tolerance is tightened and agrees with an independent stiff integrator."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rotordiag.simulator.train import dynamics
from rotordiag.simulator.train.dynamics import build_kernel, initial_state, linear_stability, simulate_train
from rotordiag.simulator.train.linear import modes

from .bench_util import bench_machine


def _whirl(sig: np.ndarray, samples_per_rev: int, speed_rpm: float) -> tuple[float, float]:
    """(pk-pk, frequency of the largest non-DC line in Hz) of one probe signal."""
    F = np.abs(np.fft.rfft(sig - sig.mean()))
    k = int(np.argmax(F[1:])) + 1
    revs = sig.shape[0] / samples_per_rev
    return float(np.ptp(sig)), k / revs * speed_rpm / 60


def test_stability_margin_of_the_reduced_train_matches_the_full_models_and_a_whip_speed_is_flagged():
    """The least log decrement the time response reports (reduced model about the static state) against the
    full finite-element model's damped modes; a speed beyond the threshold is said in the run's message."""
    train = bench_machine()
    for speed in (3000.0, 4500.0):
        kern = build_kernel(train, speed, 12)
        logdec, f_hz = linear_stability(kern, speed)
        full = modes(train, speed)
        low = full.frequency_hz < 500.0  # the shaft's own high modes (≥ 10 kHz, undamped) are not in the basis
        k = int(np.argmin(np.where(low, full.log_decrement, np.inf)))
        assert logdec == pytest.approx(float(full.log_decrement[k]), abs=0.005)
        assert f_hz == pytest.approx(float(full.frequency_hz[k]), rel=0.01)
        run = simulate_train(kern, speed, transient_revs=1, record_revs=1, samples_per_rev=16)
        assert run.log_decrement == logdec
        if speed == 3000.0:
            assert logdec > 0 and run.message == "" and run.inputs["method"] == "etd"
        else:
            assert logdec < 0
            assert "beyond the linear stability threshold" in run.message
            assert run.inputs["method"] == "dopri"  # the frozen-linearisation ETD is not used in whip
            assert 20.0 < f_hz < 60.0  # the first bending mode's whirl (≈ 34 Hz)


def test_error_controlled_exponential_integrator_meets_its_tolerance_in_stable_operation():
    """Step-doubling ETDRK4 at rtol 1e-7 against Dormand–Prince at 1e-10 over the first revolutions from the
    static state (the start-up transient, the most demanding part of a stable run)."""
    train = bench_machine()
    kern = build_kernel(train, 3000.0, 12)
    kw = dict(transient_revs=0, record_revs=6, samples_per_rev=32)
    a = simulate_train(kern, 3000.0, method="etd_adaptive", rtol=1e-7, **kw)
    ref = simulate_train(kern, 3000.0, method="dopri", rtol=1e-10, atol_m=1e-14, **kw)
    coarse = simulate_train(kern, 3000.0, method="etd_adaptive", rtol=1e-3, **kw)
    assert a.ok and ref.ok and a.inputs["method"] == "etd_adaptive"
    err = np.abs(a.journal_m - ref.journal_m).max()
    assert err < 1e-3 * np.ptp(ref.journal_m)
    assert a.nfev > coarse.nfev  # a tighter tolerance takes more steps


@pytest.mark.slow
def test_whip_limit_cycle_converges_with_tolerance_and_agrees_with_lsoda():
    """4500 r/min (least log decrement −0.23): 80 revolutions from the static state reach the whip limit
    cycle. Its pk-pk and whirl frequency at every probe agree within 1 % at rtol 1e-5 and 1e-7, and with
    scipy's LSODA (stiff BDF, its own Jacobian) at rtol 1e-9 on the same reduced equations."""
    train = bench_machine()
    speed, spr, revs = 4500.0, 32, 80
    kern = build_kernel(train, speed, 12)
    runs = [simulate_train(kern, speed, transient_revs=revs - 8, record_revs=8, samples_per_rev=spr, rtol=rt,
                           record_state=True) for rt in (1e-5, 1e-7)]
    assert all(r.ok for r in runs)
    s0 = initial_state(kern, speed)
    work = np.empty(s0.shape[0])

    def rhs(t, s):
        dynamics._rhs(t, s, *kern.args, work)
        return work.copy()

    t_rec = runs[1].time_s
    sol = solve_ivp(rhs, (0.0, t_rec[-1]), s0, method="LSODA", t_eval=t_rec, rtol=1e-9, atol=1e-13)
    assert sol.success
    sup = kern.red.support_index
    lsoda = np.stack([sol.y[j: j + 2].T for j in sup], axis=1) - kern.red.assembly.support_centres_m[None]
    clear = kern.clear
    for b in range(len(sup)):
        for ax in range(2):
            pp_ref, f_ref = _whirl(lsoda[:, b, ax], spr, speed)
            for r in runs:
                pp, f = _whirl(r.journal_m[:, b, ax], spr, speed)
                assert pp == pytest.approx(pp_ref, rel=0.01)
                assert f == pytest.approx(f_ref, rel=0.01)
    pp_b1 = np.ptp(runs[1].journal_m[:, 0, 0])
    assert pp_b1 > 1.5 * clear[0]  # a developed whip, not the forced response (≈ 5 µm at 3000 r/min)
    assert _whirl(runs[1].journal_m[:, 0, 0], spr, speed)[1] < 0.6 * speed / 60  # sub-synchronous
