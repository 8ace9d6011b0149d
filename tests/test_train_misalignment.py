"""The headline statements of docs/train-misalignment.md, recomputed with the script that made the page
(``benchmarks/train_misalignment.py``, loaded by path): each test fails when its statement stops being true."""
from __future__ import annotations

import math

import numpy as np
import pytest

from .bench_util import load_benchmark

tm = load_benchmark("train_misalignment")


def _case(name: str, arrangement: str, coupling: str, kind: str, direction: str, value: float, dynamic: bool = False):
    tr, speed, c3 = tm.base_train(name, arrangement, coupling)
    row = tm.run_case(tm.moved(tr, kind, direction, value, c3), speed, dynamic)
    assert "error" not in row, row.get("error")
    return {**row, "c_um": c3 * 1e6}


def test_a_downward_rigid_offset_unloads_bearing_3_and_loads_bearing_2():
    """Four bearings, rigid coupling, the exciter's bearings 0.5 c down: bearing 3 (the exciter's coupling end) unloads
    until the journal pulls it upward; bearing 2 (the generator's coupling end) takes the difference; the total
    still equals the weight (the outboard bearings move little)."""
    aligned = _case("gen200_2pole", "four", "rigid", "parallel", "down", 0.0)
    down = _case("gen200_2pole", "four", "rigid", "parallel", "down", 0.5)
    b1, b2, b3, b4 = (np.array(down["load_y_kn"]) - np.array(aligned["load_y_kn"]))
    assert down["load_y_kn"][2] < 0 < aligned["load_y_kn"][2] + 5.0       # lifted (the journal pulls it down)
    assert b3 < -10.0 and b2 > 10.0                                      # kN: the transfer from 3 to 2
    assert abs(b1) < 0.1 * abs(b3) and abs(b2 + b3) < 0.2 * abs(b3)      # the outboard bearing 1 barely moves
    assert math.isclose(sum(down["load_y_kn"]), sum(aligned["load_y_kn"]), rel_tol=1e-6)


def test_a_sideways_offset_moves_bearing_3s_journal_across_its_clearance_more_than_its_load():
    """A sideways rigid offset of 0.5 c moves bearing 3's journal horizontally by a large part of the clearance (the
    centreline shows it) while its vertical load changes by a few kN."""
    aligned = _case("gen200_2pole", "four", "rigid", "parallel", "sideways", 0.0)
    side = _case("gen200_2pole", "four", "rigid", "parallel", "sideways", 0.5)
    c_um = side["c_um"]
    dx = side["journal_um"][2][0] - aligned["journal_um"][2][0]
    assert abs(dx) > 0.25 * c_um
    assert abs(side["load_y_kn"][2] - aligned["load_y_kn"][2]) < 0.1 * side["load_y_kn"][1]


def test_three_bearings_a_downward_offset_unloads_the_single_exciter_bearing_and_takes_its_margin():
    """Three bearings (gen50_2pole's exciter overhung on bearing 3): lowering bearing 3 by 0.5 c unloads it and the
    least-damped mode's log decrement (film coefficients) falls from positive to below zero at rated speed — the
    field's "an unloaded bearing whirls" — while the same train on four bearings keeps its margin."""
    aligned = _case("gen50_2pole", "three", "rigid", "parallel", "down", 0.0)
    down = _case("gen50_2pole", "three", "rigid", "parallel", "down", 0.5)
    assert down["load_y_kn"][2] < 0.5 * aligned["load_y_kn"][2]
    assert aligned["log_dec"] > 0.03 and down["log_dec"] < 0.0
    four = _case("gen50_2pole", "four", "rigid", "parallel", "down", 0.5)
    assert four["log_dec"] > 0.3


@pytest.mark.slow
def test_a_flexible_offsets_2x_grows_with_the_offset_and_a_rigid_offsets_does_not():
    """gen50_2pole at 3000 r/min, four bearings: with the flexible coupling 2X at bearing 3 grows about linearly with δ
    (the double-engagement kinematic 2X) and the 2X/1X rule of thumb reads it; with the rigid coupling the same offset
    leaves 2X/1X at the coupling bearings below the rule's 0.5."""
    flex = [_case("gen50_2pole", "four", "flexible", "parallel", "down", f, dynamic=True) for f in (0.0, 0.1, 0.5)]
    two = [r["two_x_um"][2] for r in flex]
    assert two[0] < two[1] < two[2]
    assert 3.5 < (two[2] - two[0]) / (two[1] - two[0]) < 6.5            # linear: 5
    assert flex[2]["ratio"][2] > 2.0
    rigid = _case("gen50_2pole", "four", "rigid", "parallel", "down", 0.5, dynamic=True)
    assert max(rigid["ratio"][1:3]) < 0.5


def test_a_vertical_angular_offset_unloads_the_exciters_outboard_bearing_and_a_flexible_coupling_takes_it_all():
    """Rigid coupling, the exciter's far end 0.2 mrad down: its outboard bearing 4 unloads and bearing 2 takes the load.
    The same angle across the flexible coupling changes no load by 0.1 kN (its angular spring carries it; the model
    gives an angular offset no kinematic forcing, docs/train-misalignment.md)."""
    aligned = _case("gen200_2pole", "four", "rigid", "parallel", "down", 0.0)
    tilted = _case("gen200_2pole", "four", "rigid", "angular", "down", 0.2)
    assert tilted["load_y_kn"][3] < aligned["load_y_kn"][3] - 1.5
    assert tilted["load_y_kn"][1] > aligned["load_y_kn"][1] + 1.5
    flex0 = _case("gen200_2pole", "four", "flexible", "parallel", "down", 0.0)
    flex = _case("gen200_2pole", "four", "flexible", "angular", "down", 0.2)
    assert np.max(np.abs(np.array(flex["load_y_kn"]) - flex0["load_y_kn"])) < 0.1
