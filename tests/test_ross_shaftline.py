"""The ROSS validation machines as shaft-line files (``benchmarks/ross_shaftline.py``, issue 48 item 5).

The files under ``benchmarks/ross_shaftlines/`` must be what the generator makes from ``MACHINES`` today, load as a
retrain would read them, and keep ROSS's masses, bearing coefficients, clearance and rated speed."""
from __future__ import annotations

import tomllib

import pytest

from rotordiag.models.plant_retrain import describe_plant
from rotordiag.simulator.shaftline import ShaftLine, rotor_mass_kg

from .bench_util import BENCH, load_benchmark

rv = load_benchmark("ross_validation")
rs = load_benchmark("ross_shaftline")


@pytest.mark.parametrize("spec", rv.MACHINES, ids=lambda s: s.name)
def test_ross_shaftline_file_is_current_and_loads(spec):
    path = BENCH / "ross_shaftlines" / f"{spec.name}.toml"
    assert tomllib.loads(path.read_text(encoding="utf-8")) == rs.shaftline_dict(spec), \
        "stale file: rerun benchmarks/ross_shaftline.py"
    desc = describe_plant(shaftline=path)
    assert desc.rated_speed_rpm == (spec.speed_rpm,)
    line = ShaftLine.from_dict(desc.shaftline)
    # ROSS's masses from the spec alone: solid steel segments (ρ 7850) plus half the coupling each
    m_gen, m_exc = rs.ross_masses_kg(spec)
    assert rotor_mass_kg(line.generator) == pytest.approx(m_gen, rel=1e-9)
    assert rotor_mass_kg(line.exciter) == pytest.approx(m_exc, rel=1e-9)
    # bearing stations: bearing 2 where ROSS's overhung hub segment starts, bearing 3 where the exciter's ends
    assert line.generator.span_m == pytest.approx(sum(s[0] for s in spec.generator[:-1]))
    assert sum(s[0] for s in line.exciter.overhang) == pytest.approx(spec.exciter[0][0])
    assert line.bearing_types == ("linear",) * 4
    for k, opt in zip(spec.bearing_stiffness_n_m, line.bearing_options, strict=True):
        assert opt["stiffness_n_m"] == [[k, 0.0], [0.0, 1.6 * k]]
        assert opt["damping_n_s_m"][1][1] == pytest.approx(4e-4 * 1.6 * k)
    assert line.clearance_m == pytest.approx(spec.clearance_um * 1e-6)
    assert (line.coupling, line.coupling_stiffness_n_m) == ("flexible", spec.coupling_stiffness_n_m)
