"""Continuation on the light-exciter plant (issue 16 items 2-3): the step-control stall, the
Δ = 0 speed branch (`aligned`) against `pin` at small Δ, and period-n orbits of its windows."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotordiag.simulator.cli import load_plant
from rotordiag.simulator.steady.rotor import RotorFamily, rotor_branches

LIGHT = Path(__file__).resolve().parent.parent / "docs" / "figures" / "light-exciter-plant.toml"


@pytest.fixture(scope="module")
def light():
    return load_plant(LIGHT)


@pytest.mark.slow
def test_delta_branch_from_002_passes_the_stall_and_the_end_fold(light):
    """Before the fix the branch from Δ = 0.02 at 1843 r/min stopped at Δ ≈ 0.0386 with "step size
    below ds_min" (on the unstable branch after the end fold, |μ| ≈ 80: the corrector's residual
    could not reach 1e-9 through the integration noise). Now it reaches the fold at Δ ≈ 0.0556
    and follows the unstable branch back below Δ = 0.035."""
    fam = RotorFamily(light, "misalignment", 1843.0, 0.02, 0.05)
    (branch, *_) = rotor_branches(fam, 0.02, 0.6, max_points=100)
    assert "step size below ds_min" not in branch.message
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert folds and folds[0].parameter == pytest.approx(0.0556, abs=5e-4)
    after = branch.values[folds[0].index + 1:]
    assert after.min() < 0.035
    assert set(branch.stability[folds[0].index + 2:]) == {"unstable"}
    assert np.all(np.abs(branch.points[-1].multipliers).max() > 50.0)


def test_pin_tends_to_aligned_as_delta_tends_to_zero(light):
    """At Δ = 0 `pin` is singular (φ'' ∝ 1/Δ) and the physically equivalent machine is `aligned`
    (the Δ = 0 speed branch of docs/reproduction.md). The `pin` orbit must approach the aligned one
    as O(Δ): the state difference shrinks tenfold from Δ = 1e-3 to 1e-4 and is ≈ Δ in size, and the
    Floquet multipliers of the aligned orbit are those of the pin orbit (which has two more, of φ)."""
    from rotordiag.simulator.steady import steady_state

    aligned = steady_state(light, 1843.0, 0.0, 0.05, mechanism="aligned")
    assert aligned.converged and aligned.stable
    keep = [i for i in range(aligned.state.size) if i not in (10, 21)]  # φ, φ' (not dynamic for aligned)
    gaps = []
    for delta in (1e-3, 1e-4):
        pin = steady_state(light, 1843.0, delta, 0.05, mechanism="pin", initial_state=aligned.state)
        assert pin.converged and pin.stable
        gaps.append(float(np.max(np.abs(pin.state[keep] - aligned.state[keep]))))
        for mu in aligned.multipliers[:6]:
            assert np.min(np.abs(pin.multipliers - mu)) < 20 * delta
    assert 0.3e-3 < gaps[0] < 3e-3
    assert gaps[1] == pytest.approx(gaps[0] / 10, rel=0.1)


@pytest.mark.slow
def test_period_three_window_at_1843_rpm_is_an_isola_between_two_folds(light):
    """The light plant's period-3 point of the Fig 14 sweep (Δ = 0.08, 1843 r/min): shot from a
    brute-force point (period 3 read from its record), its branch closes on itself; the window is
    bounded by saddle-node folds at Δ ≈ 0.0797 and 0.0876, with no period doubling on it."""
    fam = RotorFamily(light, "misalignment", 1843.0, 0.08, 0.05)
    (branch, *rest) = rotor_branches(fam, 0.08, 0.16, bounds=(0.02, 0.16), start_revs=400, max_points=120)
    assert branch.n_periods == 3 and not rest
    assert branch.message.startswith("closed")
    kinds = {b.kind for b in branch.bifurcations}
    assert kinds == {"fold"}
    folds = [b.parameter for b in branch.bifurcations]
    assert min(folds) == pytest.approx(0.0797, abs=3e-4) and max(folds) == pytest.approx(0.0876, abs=3e-4)
    assert min(branch.values) >= min(folds) - 1e-6 and max(branch.values) <= max(folds) + 1e-6
    assert "stable" in set(branch.stability) and "unstable" in set(branch.stability)
