"""Dataset specs that sample machine families: several base plants (presets, shaft-line files, an inline
shaft line) and log-uniform parameter scaling, recorded per sample (issue 13 item 5, docs/datasets.md)."""
from __future__ import annotations

import json
import math
import tomllib
from collections import Counter
from pathlib import Path

import h5py
import numpy as np
import pytest

from rotordiag.simulator import Plant, shaftline
from rotordiag.simulator.dataset.design import build_design
from rotordiag.simulator.dataset.generate import generate
from rotordiag.simulator.dataset.spec import SpecError, load_spec, parse_spec

HEAD = """\
[design]
method = "{method}"
{n_line}
seed = 5

[operating]
speed_rpm = {speed}
misalignment = {delta}
mechanism = {mechanism}

[measurement]
sample_rate_hz = 1024
duration_revs = 4

[simulation]
transient_revs = 20
record_revs_min = 6
"""


def _spec(plant_toml: str, *, method: str = "sobol", n: int | None = 64, speed: str = "{min = 1500, max = 2100}",
          delta: str = "{min = 0.0, max = 0.4}", mechanism: str = '{offset = 1, flexible = 1}') -> str:
    n_line = f"n_samples = {n}" if n is not None else ""
    return HEAD.format(method=method, n_line=n_line, speed=speed, delta=delta, mechanism=mechanism) + plant_toml


FAMILY = """
[plant]
presets = {gen50_2pole = 1, gen200_2pole = 2, gen600_4pole = 1}
[plant.scale]
generator_stiffness_n_m = {min = 0.5, max = 2.0}
bearing_length_m = {min = 0.8, max = 1.25}
[plant.perturb]
asymmetry = 0.1
"""


def _preset_plant(name: str) -> dict:
    return shaftline.to_plant(shaftline.preset(name)).to_dict()


def test_family_draws_each_preset_by_weight_and_scales_log_uniformly():
    design = build_design(parse_spec(_spec(FAMILY)))
    pts = [design[i] for i in range(len(design))]
    counts = Counter(p.plant_source for p in pts)
    # 64 Sobol points, weights 1:2:1 → a stratified choice: exactly 16 / 32 / 16
    assert counts == {"preset:gen50_2pole": 16, "preset:gen200_2pole": 32, "preset:gen600_4pole": 16}
    logs = []
    for p in pts:
        base = _preset_plant(p.plant_source.removeprefix("preset:"))
        f_k = p.plant["generator_stiffness_n_m"] / base["generator_stiffness_n_m"]
        f_l = np.array(p.plant["bearing_length_m"]) / np.array(base["bearing_length_m"])
        assert 0.5 <= f_k <= 2.0
        assert np.allclose(f_l, f_l[0], rtol=1e-12) and 0.8 <= f_l[0] <= 1.25  # one factor for all bearings
        assert abs(p.plant["asymmetry"] / base["asymmetry"] - 1) <= 0.1 + 1e-12
        # unscaled, unperturbed fields are the preset's own
        assert p.plant["exciter_mass_kg"] == base["exciter_mass_kg"]
        assert Plant.from_dict(p.plant)  # every sample is a valid plant
        logs.append(math.log(f_k))
    # log-uniform: the median factor is near the geometric mean 1 (not the arithmetic 1.25)
    assert abs(np.median(logs)) < 0.1
    assert min(logs) < math.log(0.6) and max(logs) > math.log(1.7)  # the range is covered
    # reproducible: a second resolution of the same text gives the same samples
    again = build_design(parse_spec(_spec(FAMILY)))
    assert all(again[i] == pts[i] for i in (0, 17, 63))


def test_grid_takes_each_family_member_as_a_level():
    plant = '\n[plant]\npresets = ["gen50_2pole", "gen600_2pole"]\n'
    design = build_design(parse_spec(_spec(plant, method="grid", n=None, speed="[1500, 1800, 2100]",
                                           delta="[0.0, 0.2]", mechanism='"offset"')))
    assert len(design) == 3 * 2 * 2
    pts = [design[i] for i in range(len(design))]
    for name in ("gen50_2pole", "gen600_2pole"):
        members = [p for p in pts if p.plant_source == f"preset:{name}"]
        assert len(members) == 6 and all(p.plant == _preset_plant(name) for p in members)
        assert sorted((p.speed_rpm, p.misalignment) for p in members) == sorted(
            (s, d) for s in (1500.0, 1800.0, 2100.0) for d in (0.0, 0.2))


def test_shaftline_files_and_inline_tables_give_the_same_plant_as_the_file(tmp_path):
    example = Path(__file__).resolve().parents[1] / "examples" / "shaftline_200mw.toml"
    (tmp_path / "a.toml").write_text(example.read_text())
    text = example.read_text().replace("0.35e-3", "0.40e-3")  # another machine: larger clearance
    (tmp_path / "b.toml").write_text(text)
    spec = tmp_path / "spec.toml"
    spec.write_text(_spec('\n[plant]\nshaftlines = {"a.toml" = 1, "b.toml" = 3}\n'))
    r = load_spec(spec)
    assert r.source_weights == {"shaftline:a.toml": 0.25, "shaftline:b.toml": 0.75}
    assert r.sources["shaftline:b.toml"].clearance_m == pytest.approx(0.40e-3)
    file_plant = shaftline.to_plant(shaftline.ShaftLine.from_file(example))
    assert r.sources["shaftline:a.toml"] == file_plant
    # the same description written inline in the spec (what the service sends)
    inline = tomllib.loads(example.read_text())
    import tomli_w

    r2 = parse_spec(_spec(tomli_w.dumps({"plant": {"shaftline": inline}})))
    assert r2.sources == {"shaftline:inline": file_plant}


def test_a_spec_without_a_family_keeps_its_identity():
    # same plant reached two ways → same samples; a family changes the hash
    one = parse_spec(_spec('\n[plant]\npreset = "gen200_2pole"\n'))
    fam = parse_spec(_spec('\n[plant]\npresets = ["gen200_2pole"]\n'))
    assert one.sources.keys() == fam.sources.keys() == {"preset:gen200_2pole"}
    d1, d2 = build_design(one), build_design(fam)
    assert all(d1[i] == d2[i] for i in range(0, 64, 9))
    plain = parse_spec(_spec(""))
    assert plain.sources.keys() == {"default"} and build_design(plain)[3].plant_source == "default"


@pytest.mark.parametrize("plant_toml, expect", [
    ('presets = ["gen999"]', "unknown shaft-line preset 'gen999'"),
    ('presets = []', "empty family"),
    ('presets = {gen50_2pole = 0}', "not all zero"),
    ('presets = ["gen50_2pole"]\npreset = "gen200_2pole"', "give one of file, shaftline, preset"),
    ('presets = ["gen50_2pole", "gen50_2pole"]', "distinct"),
    ('[plant.scale]\nclearance_m = {min = 0.01, max = 2}', "factors within [0.1, 10]"),
    ('[plant.scale]\nbearing_model = {min = 0.5, max = 2}', "'bearing_model' cannot be scaled"),
    ('[plant.scale]\nclearance_m = {min = 2, max = 0.5}', "empty range"),
    ('[plant.set]\nasymmetry = 0.2\n[plant.scale]\nasymmetry = {min = 0.5, max = 4}',
     "plant.scale.asymmetry = 0.5..4 gives an invalid plant at its extreme"),
    ('shaftline = {generator = {segments = [[1.0, -0.3]]}, exciter = {segments = [[1.0, 0.3]]}}',
     "diameter_m must be a positive number"),
])
def test_bad_family_or_scale_is_refused_with_the_key_named(plant_toml, expect):
    table = plant_toml if plant_toml.startswith("[") else "[plant]\n" + plant_toml
    with pytest.raises(SpecError) as exc:
        parse_spec(_spec("\n" + table + "\n"))
    assert expect in str(exc.value)


def test_grid_refuses_weights_and_scaling():
    grid = dict(method="grid", n=None, speed="[1500]", delta="[0.1]", mechanism='"offset"')
    with pytest.raises(SpecError, match="weights need a random design"):
        parse_spec(_spec('\n[plant]\npresets = {gen50_2pole = 1}\n', **grid))
    with pytest.raises(SpecError, match="plant.scale needs a random design"):
        parse_spec(_spec('\n[plant.scale]\nclearance_m = {min = 0.5, max = 2}\n', **grid))


def test_two_shaftline_files_with_one_name_are_refused(tmp_path):
    example = Path(__file__).resolve().parents[1] / "examples" / "shaftline_200mw.toml"
    for d in ("x", "y"):
        (tmp_path / d).mkdir()
        (tmp_path / d / "m.toml").write_text(example.read_text())
    spec = tmp_path / "spec.toml"
    spec.write_text(_spec('\n[plant]\nshaftlines = ["x/m.toml", "y/m.toml"]\n'))
    with pytest.raises(SpecError, match="two files are named 'm.toml'"):
        load_spec(spec)


def test_generated_family_dataset_records_source_and_plant_per_sample(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text(_spec(FAMILY, n=4))
    out = tmp_path / "fam.h5"
    summary = generate(spec, out, n_workers=0, progress=False)
    assert summary.complete
    design = build_design(load_spec(spec))
    with h5py.File(out, "r") as f:
        src = [s.decode() for s in f["parameters/plant_source"][...]]
        assert src == [design[i].plant_source for i in range(4)]
        for i in range(4):
            p = design[i].plant
            assert f["parameters/plant/generator_stiffness_n_m"][i] == p["generator_stiffness_n_m"]
            assert np.array_equal(f["parameters/plant/bearing_length_m"][i], p["bearing_length_m"])
            # the stored values rebuild the sample's plant exactly (plant_id = hash of every value)
            assert f["parameters/plant_id"][i].decode() == Plant.from_dict(p).plant_id()
        sources = json.loads(f.attrs["plant_sources_json"])
        assert set(sources) == {"preset:gen50_2pole", "preset:gen200_2pole", "preset:gen600_4pole"}
        assert sources["preset:gen200_2pole"]["weight"] == 0.5
        assert sources["preset:gen50_2pole"]["plant"] == _preset_plant("gen50_2pole")
