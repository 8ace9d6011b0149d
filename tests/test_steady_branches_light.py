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
