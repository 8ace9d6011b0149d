"""Plants from a shaft-line description (issue 13 item 5): beam model, reduction, presets, CLI."""
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from rotordiag.simulator import Plant, simulate
from rotordiag.simulator import shaftline as sl


def test_beam_model_uniform_rotor_matches_analytic_pinned_beam():
    L, d = 6.0, 0.5
    E, rho = sl.MATERIALS["steel"]
    r = sl.reduce_rotor(sl.Rotor(((L, d),)))
    area, inertia = math.pi * d * d / 4, math.pi * d ** 4 / 64
    f1 = math.pi / (2 * L * L) * math.sqrt(E * inertia / (rho * area))  # π²/(2π L²)·√(EI/ρA)
    assert r.first_pinned_hz == pytest.approx(f1, rel=1e-4)
    m = rho * area * L
    assert r.disk_kg == pytest.approx(m / 2, rel=1e-4)  # modal mass of sin(πx/L) normalised to 1
    assert r.journal_a_kg + r.disk_kg + r.journal_b_kg == pytest.approx(m, rel=1e-12)
    assert r.journal_a_kg == pytest.approx(r.journal_b_kg, rel=1e-9)
    # the lumped disk on two half-spans reproduces the first pinned frequency exactly
    assert math.sqrt(2 * r.half_span_stiffness_n_m / r.disk_kg) / (2 * math.pi) == pytest.approx(f1, rel=1e-4)


def test_body_mass_off_centre_moves_the_journal_split_like_statics():
    rotor = sl.Rotor(((4.0, 0.4),), body_masses=((1.0, 2000.0),))
    r = sl.reduce_rotor(rotor)
    E, rho = sl.MATERIALS["steel"]
    shaft = rho * math.pi * 0.16 / 4 * 4.0
    # static reactions: shaft half/half, body 3/4 to bearing a; journals carry the non-modal rest in that ratio
    ra = shaft / 2 + 2000.0 * 0.75
    total = shaft + 2000.0
    assert r.journal_a_kg / (r.journal_a_kg + r.journal_b_kg) == pytest.approx(ra / total, rel=1e-9)


@pytest.mark.parametrize("name", sorted(sl.PRESETS))
@pytest.mark.parametrize("kb", [1e9, 3e9])
def test_lumped_plant_matches_beam_train_first_two_critical_speeds(name, kb):
    line = sl.preset(name)
    plant = sl.to_plant(line)
    fe = sl.train_critical_speeds(line, kb)
    lu = sl.lumped_critical_speeds(plant, kb)
    np.testing.assert_allclose(lu, fe, rtol=0.05)  # measured: ≤ 3.4 % at 1e9, ≤ 1.6 % at 3e9 N/m
    assert 5 < fe[0] < fe[1] < 80


def test_example_file_and_preset_give_the_same_plant_and_it_runs():
    a = sl.to_plant(sl.ShaftLine.from_file("examples/shaftline_200mw.toml"))
    b = sl.to_plant(sl.preset("gen200_2pole"))
    for k, v in a.to_dict().items():
        np.testing.assert_allclose(np.asarray(v, dtype=float) if k != "bearing_model" else 0,
                                   np.asarray(b.to_dict()[k], dtype=float) if k != "bearing_model" else 0, rtol=1e-8)
    res = simulate(a, 1950.0, 0.1, 0.05, mechanism="flexible", transient_revs=100, record_revs=4, samples_per_rev=32,
                   settle_tol=1e-7)
    assert res.status == "ok"


@pytest.mark.parametrize("bad, match", [
    ({"exciter": {"segments": [[1, 0.3]]}}, r"\[generator\]"),
    ({"generator": {"segments": []}, "exciter": {"segments": [[1, 0.3]]}}, "generator.segments"),
    ({"generator": {"segments": [[1, -0.3]]}, "exciter": {"segments": [[1, 0.3]]}}, "diameter_m"),
    ({"generator": {"segments": [[1, 0.3]], "body_masses": [[2.0, 10]]}, "exciter": {"segments": [[1, 0.3]]}},
     "outside the span"),
    ({"generator": {"segments": [[1, 0.3]]}, "exciter": {"segments": [[1, 0.3]]}, "material": "wood"}, "material"),
    ({"generator": {"segments": [[1, 0.3]]}, "exciter": {"segments": [[1, 0.3]]}, "coupling": {"type": "gear"}},
     "coupling.type"),
    ({"generator": {"segments": [[1, 0.3]]}, "exciter": {"segments": [[1, 0.3]]}, "bearing": {}}, "unknown"),
])
def test_bad_shaft_lines_are_named(bad, match):
    with pytest.raises(ValueError, match=match):
        sl.ShaftLine.from_dict(bad)


def test_cli_writes_the_plant(tmp_path):
    from rotordiag.cli import app

    out = tmp_path / "p.toml"
    r = CliRunner().invoke(app, ["plant", "from-shaftline", "--preset", "gen50_2pole", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "beam model" in r.output
    assert Plant.from_file(out) == sl.to_plant(sl.preset("gen50_2pole"))
    r = CliRunner().invoke(app, ["plant", "from-shaftline", "--out", str(out)])
    assert r.exit_code != 0 and "FILE or --preset" in r.output
