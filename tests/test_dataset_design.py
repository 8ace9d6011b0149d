"""Sampling designs and per-sample seeds."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from rotordiag.simulator import Plant
from rotordiag.simulator.dataset.design import build_design, sample_seed
from rotordiag.simulator.dataset.spec import parse_spec

BASE = """
[design]
method = "{method}"
{n_line}
seed = {seed}
[operating]
speed_rpm = {speed}
misalignment = {delta}
unbalance = 0.05
mechanism = {mech}
{perturb}
[measurement]
sample_rate_hz = 2048
duration_s = 0.5
"""


def make(method="sobol", n=64, seed=3, speed="{min = 1200, max = 3000}", delta="{min = 0.0, max = 0.6}",
         mech='"rigid"', perturb=""):
    n_line = f"n_samples = {n}" if n is not None else ""
    return build_design(parse_spec(BASE.format(method=method, n_line=n_line, seed=seed, speed=speed,
                                               delta=delta, mech=mech, perturb=perturb)))


def column(design, name):
    return np.array([getattr(design[i], name) for i in range(len(design))])


def test_grid_is_the_full_factorial_in_documented_order():
    d = make("grid", None, speed="{min = 1200, max = 3000, n = 4}", delta="[0.0, 0.1, 0.4]", mech='["pin", "rigid"]')
    expected = list(itertools.product([1200.0, 1800.0, 2400.0, 3000.0], [0.0, 0.1, 0.4], ["pin", "rigid"]))
    got = [(d[i].speed_rpm, d[i].misalignment, d[i].mechanism) for i in range(len(d))]
    assert len(d) == 24
    assert got == [(float(a), float(b), c) for a, b, c in expected]


@pytest.mark.parametrize("method", ["sobol", "lhs"])
def test_random_designs_are_reproducible_and_seeded(method):
    a, b, c = make(method, seed=3), make(method, seed=3), make(method, seed=4)
    assert np.array_equal(column(a, "speed_rpm"), column(b, "speed_rpm"))
    assert not np.array_equal(column(a, "speed_rpm"), column(c, "speed_rpm"))
    s = column(a, "speed_rpm")
    assert s.min() >= 1200 and s.max() <= 3000


def test_lhs_puts_one_point_in_each_stratum():
    n = 50
    d = make("lhs", n=n)
    for name, lo, hi in (("speed_rpm", 1200, 3000), ("misalignment", 0.0, 0.6)):
        strata = np.floor((column(d, name) - lo) / (hi - lo) * n).astype(int)
        assert sorted(strata) == list(range(n))


def test_sobol_mechanism_weights_are_exact_on_a_power_of_two():
    # scrambled Sobol points with N = 2^8 put exactly N/4 points in [0, 1/4) in each coordinate
    d = make("sobol", n=256, mech="{pin = 1, rigid = 3}")
    mech = [d[i].mechanism for i in range(len(d))]
    assert mech.count("pin") == 64 and mech.count("rigid") == 192


def test_list_levels_are_equally_likely():
    d = make("sobol", n=128, delta="[0.0, 0.2, 0.4, 0.8]")
    values, counts = np.unique(column(d, "misalignment"), return_counts=True)
    assert list(values) == [0.0, 0.2, 0.4, 0.8] and list(counts) == [32, 32, 32, 32]


def test_perturbations_stay_in_bounds_and_vary_per_bearing():
    perturb = "[plant.perturb]\ngenerator_mass_kg = 0.2\nbearing_radius_m = 0.1"
    d = make("lhs", n=40, perturb=perturb)
    base = Plant.default()
    m = np.array([d[i].plant["generator_mass_kg"] for i in range(40)])
    r = np.array([d[i].plant["bearing_radius_m"] for i in range(40)])
    assert np.all(np.abs(m / base.generator_mass_kg - 1) <= 0.2) and m.std() > 0
    ratio = r / np.array(base.bearing_radius_m)
    assert np.all(np.abs(ratio - 1) <= 0.1)
    assert not np.allclose(ratio[:, 0], ratio[:, 1])  # each bearing its own draw
    # untouched fields keep the base value, and every sample is a valid plant
    assert all(d[i].plant["exciter_mass_kg"] == base.exciter_mass_kg for i in range(40))
    ids = {Plant.from_dict(d[i].plant).plant_id() for i in range(40)}
    assert len(ids) == 40


def test_sample_seeds_do_not_depend_on_the_number_of_samples():
    small, large = make("sobol", n=8), make("sobol", n=64)
    assert [small[i].sample_seed for i in range(8)] == [large[i].sample_seed for i in range(8)]
    seeds = [large[i].sample_seed for i in range(64)]
    assert len(set(seeds)) == 64
    assert seeds[5] == sample_seed(3, 5) != sample_seed(4, 5)


def test_index_out_of_range():
    with pytest.raises(IndexError, match="out of range"):
        make("sobol", n=8)[8]


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=25, deadline=None)
@given(lo=st.floats(100, 5999), width=st.floats(0, 3000), dlo=st.floats(0, 0.89), seed=st.integers(0, 2**62),
       method=st.sampled_from(["sobol", "lhs"]), n=st.integers(1, 40))
def test_random_designs_stay_inside_any_valid_range(lo, width, dlo, seed, method, n):
    hi = min(lo + width, 6000.0)
    d = make(method, n=n, seed=seed, speed=f"{{min = {lo!r}, max = {hi!r}}}", delta=f"{{min = {dlo!r}, max = 0.9}}")
    s, m = column(d, "speed_rpm"), column(d, "misalignment")
    assert len(d) == n
    assert np.all((s >= lo) & (s <= hi)) and np.all((m >= dlo) & (m <= 0.9))
