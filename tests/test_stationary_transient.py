"""The stationary transient of samples whose shooting start falls back (issue 16 item 4).

A fallback sample (no stable period-1 orbit: whirl, quasi-periodic, chaotic) ends its transient once
the journals' motion statistics are stationary (``simulator.steady.attractor``) instead of after all
400 revolutions; how close its features are to the 400-revolution record is measured by
``benchmarks/bench_dataset.py --steady-start`` (docs/datasets.md). These tests check the mechanics.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rotordiag.simulator import Plant, build_system
from rotordiag.simulator.dataset.spec import SpecError, parse_spec
from rotordiag.simulator.dataset.worker import SimulationSettings
from rotordiag.simulator.steady.attractor import (
    STATIONARY_BLOCK,
    STATIONARY_MIN_REVS,
    STATIONARY_WINDOW_REVS,
    STATIONARY_WINDOWS,
    UNSTABLE_GROWTH,
    record_start,
    settle_on_attractor,
)
from rotordiag.simulator.steady.start import steady_start

SPEC = """
[design]
method = "sobol"
n_samples = 4
seed = 1
[operating]
speed_rpm = {min = 1500, max = 2500}
misalignment = 0.1
unbalance = 0.05
[measurement]
sample_rate_hz = 2560.0
duration_s = 0.5
[simulation]
"""


@pytest.fixture(scope="module")
def period_one():
    return build_system(Plant.default(), 1950.0, 0.02, 0.05, mechanism="pin")


@pytest.fixture(scope="module")
def whirl():
    """Above the whirl threshold: the period-1 orbit is unstable (max |μ| ≈ 1.049)."""
    return build_system(Plant.default(), 2800.0, 0.0, 0.05, mechanism="aligned")


@pytest.fixture(scope="module")
def slow_whirl():
    """Just above the threshold (max |μ| ≈ 1.016): the whirl grows slowly from rest."""
    return build_system(Plant.default(), 2450.0, 0.0, 0.05, mechanism="aligned")


def test_a_converging_motion_stops_at_the_minimum_on_its_attractor(period_one):
    st = settle_on_attractor(period_one, period_one.initial_state(), 400)
    assert st.status == "ok" and st.stationary
    # the first revolution at which the test can pass: two blocks, then the further windows in a row
    first = max(STATIONARY_MIN_REVS, (2 * STATIONARY_BLOCK + STATIONARY_WINDOWS - 1) * STATIONARY_WINDOW_REVS)
    assert st.revs == first and st.change <= 1e-4
    shot = steady_start(period_one, 400)
    assert shot.path == "shooting"
    # after that many revolutions from rest the state is on the period-1 orbit (to the transient's decay)
    assert np.max(np.abs(st.state[:10] - shot.state[:10])) < 1e-4  # max |μ| ≈ 0.93: 0.93^128 ≈ 1e-4


def test_a_motion_that_is_not_stationary_gets_the_whole_transient(period_one):
    # a tolerance below the integrator's own revolution-to-revolution noise is never met
    st = settle_on_attractor(period_one, period_one.initial_state(), 3 * STATIONARY_WINDOW_REVS + 5, tol=1e-15)
    assert not st.stationary and st.revs == 3 * STATIONARY_WINDOW_REVS + 5
    assert settle_on_attractor(period_one, period_one.initial_state(), 0).revs == 0
    with pytest.raises(ValueError, match="tol"):
        settle_on_attractor(period_one, period_one.initial_state(), 10, tol=0.0)


def test_a_slowly_growing_whirl_looks_stationary_early_so_it_keeps_the_whole_transient(slow_whirl):
    """The whirl at max |μ| ≈ 1.016 grows so slowly that 64 revolutions from rest pass the test: the
    minimum ln(UNSTABLE_GROWTH) / ln|μ| (≈ 423 revolutions here, more than the transient) is what keeps it."""
    early = settle_on_attractor(slow_whirl, slow_whirl.initial_state(), 2 * STATIONARY_WINDOW_REVS, min_revs=0,
                                windows=1, block=1)
    assert early.stationary  # the statistics alone would stop here
    fixed = steady_start(slow_whirl, 400)
    assert 1.0 < fixed.max_multiplier < UNSTABLE_GROWTH ** (1 / 400)
    st = record_start(slow_whirl, 400)
    assert st.transient_revs == fixed.transient_revs and st.note == fixed.note and np.array_equal(st.state, fixed.state)


def test_record_start_settles_only_fallbacks_without_a_stable_orbit(whirl, period_one):
    fixed = steady_start(whirl, 200)
    assert fixed.path == "integrate" and fixed.max_multiplier > 1.0
    st = record_start(whirl, 200)
    used = int(st.note.split()[1].split("/")[0])
    assert st.note.startswith(f"transient {used}/200 revs (")
    grow = math.ceil(math.log(UNSTABLE_GROWTH) / math.log(fixed.max_multiplier))
    assert st.transient_revs == 0 and max(grow, STATIONARY_MIN_REVS) <= used <= 200
    assert st.note.endswith(fixed.note) and st.path == "integrate"
    same = record_start(whirl, 200, transient_stop="fixed")
    assert same.transient_revs == fixed.transient_revs and np.array_equal(same.state, fixed.state)
    assert record_start(whirl, 200, "integrate").transient_revs == 200
    shot = record_start(period_one, 400)  # a shooting start is left alone
    assert shot.path == "shooting" and shot.transient_revs == 0 and shot.note == ""
    with pytest.raises(ValueError, match="transient_stop"):
        record_start(whirl, 200, transient_stop="adaptive")


def test_spec_key_default_refusal_and_hash():
    default = parse_spec(SPEC)
    assert default.spec.simulation.transient_stop == "fixed"          # opt-in: the default is the old behaviour
    assert SimulationSettings.from_spec(default.spec).transient_stop == "fixed"
    fixed = parse_spec(SPEC + 'transient_stop = "fixed"\n')
    assert fixed.spec_hash == default.spec_hash                        # the old hash
    stationary = parse_spec(SPEC + 'transient_stop = "stationary"\n')
    assert stationary.spec_hash != default.spec_hash
    assert SimulationSettings.from_spec(stationary.spec).transient_stop == "stationary"
    with pytest.raises(SpecError, match="transient_stop"):
        parse_spec(SPEC + 'transient_stop = "early"\n')
    s = dataclasses.replace(SimulationSettings.from_spec(fixed.spec))
    assert s.transient_stop == "fixed"
