"""Retraining for one plant (issue 48 item 3): the plant's dataset spec, its held-out report set, the decision
"better", activation only if better (409 / exit 2 otherwise, force recorded), rollback, and the progress's ETA."""
from __future__ import annotations

import datetime as dt
import json
import math
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from rotordiag.models.plant_retrain import (
    FLOOR_CONFIDENT_TWO_BANDS_OFF,
    FLOOR_DETECTION_RATE,
    FLOOR_FALSE_ALARM_RATE,
    PLANT_TOLERANCES,
    STAGE_SECONDS,
    TRAIN_STAGE_SECONDS,
    TRAIN_TOLERANCES,
    StagedProgress,
    decide,
    describe_plant,
    held_out_cases,
    paired_bootstrap,
    plant_dataset_spec,
    report_conditions,
)
from rotordiag.models.registry import ActivationRefused, Registry, shipped_registry_dir
from rotordiag.models.robustness import CONDITIONS, Outcome
from tests.service_util import auth, make_settings

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "shaftline_200mw.toml"
NAMES = ["aligned", "slight", "moderate", "severe"]
EDGES = np.array([0.05, 0.15, 0.35])


# --- the plant's dataset and its held-out set ----------------------------------------------------------

def test_a_preset_plants_spec_is_its_shaft_train_at_its_rated_speeds_within_tolerances():
    """gen600_4pole runs at 1500/1800 r/min: the sweep covers 0.8 × 1500 … 1.05 × 1800 r/min (run-up, off-rated),
    on its own finite-element shaft train, perturbed within what a manufacturer states (spans and diameters
    within ±2 %, clearance and oil wider), rigid and flexible couplings; the spec parses."""
    import tomli_w

    from rotordiag.simulator.dataset.spec import parse_spec
    from rotordiag.simulator.shaftline import preset
    from rotordiag.simulator.train.plant import TRAIN_PERTURBABLE, TrainPlant

    plant = describe_plant(preset="gen600_4pole")
    assert plant.rated_speed_rpm == (1500.0, 1800.0) and plant.is_train
    spec = plant_dataset_spec(plant, n_samples=40, seed=3)
    resolved = parse_spec(tomli_w.dumps(spec))
    assert resolved.spec.plant.model == "train"
    sp = resolved.spec.operating.speed_rpm
    assert (sp.min, sp.max) == (pytest.approx(1200.0), pytest.approx(1890.0))
    assert resolved.base_plant == TrainPlant.of(preset("gen600_4pole"))
    assert resolved.spec.design.n_samples == 40 and resolved.spec.design.seed == 3
    tol = spec["plant"]["perturb"]
    assert tol == TRAIN_TOLERANCES and set(tol) <= set(TRAIN_PERTURBABLE)
    for name in ("generator_span_m", "exciter_span_m", "generator_diameter_m", "exciter_diameter_m"):
        assert 0.0 < tol[name] <= 0.02, name
    assert tol["clearance_m"] > 0.02 and tol["viscosity_pa_s"] > 0.02
    assert set(spec["operating"]["mechanism"]) == {"rigid", "flexible"}       # the preset names no coupling
    assert spec["measurement"]["bearings"] == [1, 2, 3, 4]
    # a quarter of the Δ levels are aligned machines: the model sees healthy ones of its plant
    levels = spec["operating"]["misalignment"]
    assert levels.count(0.0) / len(levels) == pytest.approx(0.25) and max(levels) == pytest.approx(0.6)


def test_the_default_plant_without_a_shaft_line_stays_the_lumped_model():
    from rotordiag.simulator import Plant

    plant = describe_plant()
    spec = plant_dataset_spec(plant, n_samples=8)
    assert not plant.is_train and spec["plant"].get("model", "lumped") == "lumped"
    assert spec["plant"]["perturb"] == PLANT_TOLERANCES and plant.base_plant() == Plant.default()
    assert set(spec["operating"]["mechanism"]) == {"pin", "rigid", "offset", "flexible"}


def test_a_shaftline_file_gives_its_train_its_coupling_and_the_users_sweep_wins(tmp_path):
    from rotordiag.simulator.shaftline import ShaftLine
    from rotordiag.simulator.train.plant import TrainPlant

    f = tmp_path / "plant.toml"
    f.write_text("rated_speed_rpm = 3000\n" + EXAMPLE.read_text())
    plant = describe_plant(shaftline=f)
    assert plant.name == "shaftline:plant.toml" and plant.rated_speed_rpm == (3000.0,)
    assert plant.base_plant() == TrainPlant.of(ShaftLine.from_file(EXAMPLE))
    spec = plant_dataset_spec(plant, sweep={"operating": {"speed_rpm": {"min": 2900, "max": 3100},
                                                          "misalignment": {"min": 0.0, "max": 0.5}}})
    assert spec["operating"]["speed_rpm"] == {"min": 2900, "max": 3100}
    assert spec["operating"]["misalignment"] == {"min": 0.0, "max": 0.5}
    # a shaft line that names its coupling is trained and reported on that coupling only
    tables = tomllib.loads(EXAMPLE.read_text())
    tables["coupling"] = {**tables.get("coupling", {}), "type": "flexible"}
    flex = describe_plant(shaftline=tables, rated_speed_rpm=3000)
    assert plant_dataset_spec(flex)["operating"]["mechanism"] == ["flexible"]
    assert {c["label_mechanism"] for c in held_out_cases(flex, 1, 0)} == {"flexible", "aligned"}
    with pytest.raises(ValueError, match="unknown train plant value"):
        describe_plant(shaftline=tables, plant_set={"generator_mass_kg": 1.0})
    with pytest.raises(ValueError, match="one way"):
        describe_plant(preset="gen50_2pole", shaftline=f)
    with pytest.raises(ValueError, match="gen600_4pole"):
        describe_plant(preset="gen999")
    bad = tmp_path / "bad.toml"
    bad.write_text("[generator\n")
    with pytest.raises(ValueError, match="not valid TOML"):
        describe_plant(shaftline=bad)


def test_held_out_cases_are_the_train_within_tolerance_at_its_speeds_and_seeded():
    plant = describe_plant(preset="gen600_4pole")
    base = plant.base_plant().to_dict()
    cases = held_out_cases(plant, 3, seed=7)
    assert len(cases) == 9 and [c["label_mechanism"] for c in cases].count("aligned") == 3
    assert {c["mechanism"] for c in cases} == {"rigid", "flexible"}
    for c in cases:
        assert c["plant"]["model"] == "train" and c["plant"]["shaftline"] == base["shaftline"]
        for name, r in TRAIN_TOLERANCES.items():
            v, v0 = np.asarray(c["plant"][name], dtype=float), np.asarray(base[name], dtype=float)
            assert np.all(np.abs(v - v0) <= r * np.abs(v0) + 1e-12), name      # a zero (no body mass) stays zero
        assert 1200.0 <= c["speed_rpm"] <= 1890.0
        aligned = c["label_mechanism"] == "aligned"
        assert (c["misalignment"] == 0.0) == aligned and (c["angular_misalignment_mrad"] == 0.0) == aligned
        assert abs(c["angular_misalignment_mrad"]) <= 0.04
    rated = [c["speed_rpm"] for i, c in enumerate(cases) if i % 2 == 0]
    assert all(min(abs(s / 1500 - 1), abs(s / 1800 - 1)) <= 0.01 for s in rated)
    assert held_out_cases(plant, 3, seed=7) == cases and held_out_cases(plant, 3, seed=8) != cases


def test_the_default_plants_held_out_cases_stay_lumped_within_its_tolerances():
    plant = describe_plant()
    base = plant.base_plant().to_dict()
    cases = held_out_cases(plant, 2, seed=7)
    assert len(cases) == 10 and [c["label_mechanism"] for c in cases].count("aligned") == 2
    for c in cases:
        for name, r in PLANT_TOLERANCES.items():
            ratio = np.asarray(c["plant"][name], dtype=float) / np.asarray(base[name], dtype=float)
            assert np.all(np.abs(ratio - 1) <= r + 1e-12), name


def test_a_held_out_train_case_is_simulated_as_the_training_sample_of_the_same_draw():
    """The report's recordings and the training data are the same physics: a held-out case run through
    ``simulate_train_case`` gives the journals that the dataset worker's train sample (same train, speed,
    offset, transient) gives — an offset case moves the exciter-side journals' mean away from the aligned case."""
    from rotordiag.models.plant_retrain import simulate_train_case

    plant = describe_plant(preset="gen600_4pole")
    c = held_out_cases(plant, 1, seed=0)[0]
    aligned = {**c, "misalignment": 0.0, "angular_misalignment_mrad": 0.0}
    d, d0 = simulate_train_case(c, 4), simulate_train_case(aligned, 4)
    assert d.shape == (7 * 128, 4, 2) and np.isfinite(d).all()
    shift_um = np.linalg.norm(d.mean(axis=0) - d0.mean(axis=0), axis=1) * 1e6
    offset_um = c["misalignment"] * c["plant"]["clearance_m"] * 1e6
    # the coupling-end journals (bearings 2, 3) move with the offset, by a fraction of it (the film and the
    # shafts take the rest), never by more than the offset itself
    assert shift_um[1:3].max() > 0.01 * offset_um and shift_um.max() < offset_um


def test_the_report_measures_every_condition_of_the_plants_own_recordings():
    names = {c.name for c in report_conditions()}
    assert {c.name for c in CONDITIONS if c.sim_set == "base"} == names
    assert "rated-machine presets" not in names and "clean" in names and "coupling journals apart" in names


# --- the decision ------------------------------------------------------------------------------------

def _outs(deltas, mechs, classes, status="confident", shown=None):
    return [Outcome(d, m, model_class=c, severity=(shown or classes)[i], status=status, interval=(d - 0.05, d + 0.05))
            for i, (d, m, c) in enumerate(zip(deltas, mechs, classes))]


def _band(d: float) -> str:
    return NAMES[int(np.searchsorted(EDGES, d, side="right"))]


def test_paired_bootstrap_tells_a_right_model_from_one_that_calls_everything_aligned():
    """A model whose class is the true band against one that answers `aligned` always: F1 difference's interval
    above 0, and false alarms equal (neither alarms on a healthy machine): difference 0."""
    rng = np.random.default_rng(0)
    mechs = ["rigid"] * 20 + ["aligned"] * 10
    deltas = [float(x) for x in rng.uniform(0.02, 0.6, 20)] + [0.0] * 10
    right = {"clean": _outs(deltas, mechs, [_band(d) for d in deltas])}
    lazy = {"clean": _outs(deltas, mechs, ["aligned"] * 30)}
    b = paired_bootstrap(right, lazy, NAMES, EDGES, mechs, draws=300)
    # macro-F1 over the bands present: the right model 1; the lazy one F1 2a/(2a + (30 − a)) on `aligned` (a machines
    # truly in that band, the rest its false positives) and 0 on every other band present
    truth = [_band(d) for d in deltas]
    a = truth.count("aligned")
    assert b["macro_f1_diff_point"] == pytest.approx(1.0 - (2 * a / (2 * a + 30 - a)) / len(set(truth)))
    assert b["macro_f1_diff"][0] > 0.3
    assert b["false_alarm_diff"] == [0.0, 0.0]


def _report(f1_new, f1_old, fa_interval, off2=0, refused=(0, 0), fa_new=0.05, fa_old=0.05, detected=1.0,
            per_condition=None):
    return {"pooled": {"new": {"n": 100, "macro_f1": f1_new, "false_alarm_rate": fa_new, "confident_two_bands_off": off2,
                               "refused": refused[0], "moderate_or_worse_detected": detected,
                               "n_moderate_or_worse": 40},
                       "active": {"n": 100, "macro_f1": f1_old, "false_alarm_rate": fa_old, "refused": refused[1]}},
            "paired_bootstrap": {"macro_f1_diff": [f1_new - f1_old - 0.05, f1_new - f1_old + 0.05],
                                 "false_alarm_diff": list(fa_interval)},
            **({} if per_condition is None else {"per_condition": {
                name: {"new": {"false_alarm_rate": fa, "confident_two_bands_off": k}, "active": {}}
                for name, (fa, k) in per_condition.items()}})}


@pytest.mark.parametrize("report, better", [
    (_report(0.80, 0.70, (-0.05, 0.03)), True),
    (_report(0.80, 0.70, (0.01, 0.09)), False),          # more false alarms beyond the interval
    (_report(0.70, 0.80, (-0.05, 0.03)), False),         # lower F1
    (_report(0.80, 0.80, (-0.05, 0.03)), False),         # not higher
    (_report(0.80, 0.70, (-0.05, 0.03), off2=1), False),  # a confident verdict two bands off
    (_report(0.80, 0.70, (-0.05, 0.03), refused=(3, 0)), False),
])
def test_better_is_higher_f1_no_more_false_alarms_and_no_confident_two_bands_off(report, better):
    d = decide(report)
    assert d["better"] is better
    assert bool(d["failed"]) is (not better)


def test_the_floors_refuse_a_model_that_is_only_better_than_a_bad_active_one():
    """The learning curve's 48-sample model: macro-F1 0.37 against the shipped 0.21, false alarms 65.5 % against
    91 % (lower beyond the interval) — better than the active model, but far above the 5 % false-alarm floor: not
    activated, and the decision says which floor and by how much."""
    d = decide(_report(0.37, 0.21, (-0.40, -0.15), fa_new=0.655, fa_old=0.91))
    assert d["better"] is False
    assert [line for line in d["failed"] if line.startswith("floor: false alarms <= 5%")] == [
        "floor: false alarms <= 5% under every condition: above it under 1 of 1 (pooled 65.5%)"]
    assert d["floors"] == {"false_alarm_rate_max": FLOOR_FALSE_ALARM_RATE, "confident_two_bands_off_max": 0,
                           "moderate_or_worse_detected_min": FLOOR_DETECTION_RATE}
    assert (FLOOR_FALSE_ALARM_RATE, FLOOR_CONFIDENT_TWO_BANDS_OFF, FLOOR_DETECTION_RATE) == (0.05, 0, 0.97)


GOOD = (0.80, 0.70, (-0.05, 0.03))


@pytest.mark.parametrize("per_condition, detected, failing", [
    # every condition at or under 5 % (1 of 20 healthy machines), detection at the floor: every floor held
    ({"clean": (0.0, 0), "SNR 15 dB": (0.05, 0)}, 0.97, None),
    # pooled 4 % would pass, but one condition alarms on 1 of 8 healthy machines (12.5 %): the per-condition floor
    ({"clean": (0.0, 0), "gains ±20 %": (0.125, 0), "SNR 15 dB": (0.0, 0)}, 1.0, "floor: false alarms"),
    # one confident verdict two bands off under one condition
    ({"clean": (0.0, 0), "keyphasor missing": (0.0, 1)}, 1.0, "floor: at most 0 confident"),
    # 95 % of the moderate-or-worse machines called slight or worse: under 97 %
    ({"clean": (0.0, 0)}, 0.95, "floor: moderate-or-worse"),
    # no moderate-or-worse machine to measure it on: not reached
    ({"clean": (0.0, 0)}, None, "floor: moderate-or-worse"),
    # no healthy machine under any condition: the false-alarm floor cannot be checked, not reached
    ({"clean": (None, 0)}, 1.0, "floor: false alarms"),
])
def test_each_floor_passes_and_fails_per_condition(per_condition, detected, failing):
    d = decide(_report(*GOOD, fa_new=0.04, detected=detected, per_condition=per_condition))
    floors = [line for line in d["failed"] + d["held"] if line.startswith("floor:")]
    assert len(floors) == 3                                 # every floor is listed, held or failed
    if failing is None:
        assert d["better"] is True and not d["failed"]
    else:
        assert d["better"] is False and [line for line in d["failed"] if line.startswith(failing)]
        assert all(line.startswith(failing) for line in d["failed"])   # the other points and floors held


def test_the_false_alarm_floor_names_the_conditions_above_it_worst_first():
    d = decide(_report(*GOOD, per_condition={"clean": (0.0, 0), "runout": (0.25, 0), "gains": (0.125, 0)}))
    (line,) = [x for x in d["failed"] if x.startswith("floor: false alarms")]
    assert line.endswith("above it under 2 of 3 (runout 25.0%, gains 12.5%)")


def test_moderate_or_worse_detection_is_counted_on_the_model_class_at_any_status():
    """Of four machines at Δ >= 0.15, three given slight or worse (one uncertain) and one called aligned: 75 %; the
    slight and healthy machines are not in it."""
    from rotordiag.models.plant_retrain import _figures

    outs = _outs([0.2, 0.3, 0.5, 0.16, 0.1, 0.0], ["rigid"] * 5 + ["aligned"],
                 ["moderate", "slight", "severe", "aligned", "aligned", "slight"])
    outs[1] = Outcome(0.3, "rigid", model_class="slight", severity="slight", status="uncertain", interval=(0.2, 0.4))
    f = _figures(outs, NAMES, EDGES)
    assert f["n_moderate_or_worse"] == 4 and f["moderate_or_worse_detected"] == pytest.approx(0.75)
    assert f["false_alarm_rate"] == 1.0


# --- activation, force, rollback ---------------------------------------------------------------------

def _registry_with_candidate(root: Path, better: bool | None) -> Registry:
    """A registry holding the shipped model as v0001 (active) plus v0002, the same model, as a plant-retrained
    version whose report says ``better`` (None: still pending)."""
    shipped = Registry(shipped_registry_dir())
    root.mkdir(parents=True)
    shutil.copytree(shipped.root / str(shipped.active_version()), root / "v0001")
    reg = Registry(root)
    reg.update_card("v0001", {"version": "v0001"})
    reg.activate("v0001")
    shutil.copytree(root / "v0001", root / "v0002")
    rep: dict = {"pending": True, "plant": "preset:gen600_4pole"} if better is None else {
        "pending": False, "plant": "preset:gen600_4pole", "compared_with": "v0001 (active)", "better": better,
        "decision": {"better": better, "failed": [] if better else ["band macro-F1 0.300 vs 0.400: not higher"]}}
    reg.update_card("v0002", {"version": "v0002", "plant_report": rep, "activated_by": None})
    (root / "v0002" / "plant_report.json").write_text(json.dumps({"decision": rep.get("decision")}))
    return reg


def test_registry_refuses_a_worse_version_unless_forced_and_rollback_restores(tmp_path):
    reg = _registry_with_candidate(tmp_path / "reg", better=False)
    with pytest.raises(ActivationRefused, match="not better.*macro-F1 0.300"):
        reg.activate("v0002")
    assert reg.active_version() == "v0001" and reg.card("v0002")["activated_by"] is None
    reg.activate("v0002", force=True)
    assert reg.active_version() == "v0002" and reg.card("v0002")["activated_by"] == "forced"
    assert reg.rollback() == "v0001" and reg.active_version() == "v0001"


def test_a_pending_report_blocks_activation_and_a_better_one_is_recorded(tmp_path):
    reg = _registry_with_candidate(tmp_path / "a", better=None)
    with pytest.raises(ActivationRefused, match="not written yet"):
        reg.activate("v0002")
    good = _registry_with_candidate(tmp_path / "b", better=True)
    good.activate("v0002")
    assert good.active_version() == "v0002" and good.card("v0002")["activated_by"] == "report"
    # an ordinary version (no plant report) activates as before, its card untouched
    good.activate("v0001")
    assert "activated_by" not in good.card("v0001")


def test_api_activate_worse_is_409_force_is_recorded_show_and_rollback(tmp_path):
    from rotordiag.service.main import create_app

    _registry_with_candidate(tmp_path / "registry", better=False)
    settings = make_settings(tmp_path, model_registry_dir=tmp_path / "registry")
    with TestClient(create_app(settings)) as c:
        r = c.post("/models/v0002/activate", headers=auth())
        assert r.status_code == 409 and "not better" in r.json()["detail"] and "force" in r.json()["detail"]
        assert c.get("/models").json()["active"] == "v0001"
        shown = c.get("/models/v0002").json()
        assert shown["plant_report"]["decision"]["better"] is False and shown["activated_by"] is None
        assert c.get("/models/v0009").status_code == 404
        r = c.post("/models/v0002/activate?force=true", headers=auth())
        assert r.status_code == 200 and r.json()["active"] == "v0002"
        assert c.get("/models/v0002").json()["activated_by"] == "forced"
        r = c.post("/models/rollback", headers=auth())
        assert r.status_code == 200 and r.json()["active"] == "v0001"


def test_cli_activate_worse_exits_2_force_works_and_show_prints_the_report(tmp_path):
    from rotordiag.cli import app

    _registry_with_candidate(tmp_path / "reg", better=False)
    run = CliRunner().invoke
    r = run(app, ["models", "activate", "v0002", "--registry", str(tmp_path / "reg")])
    assert r.exit_code == 2 and "not better" in r.output
    r = run(app, ["models", "activate", "v0002", "--registry", str(tmp_path / "reg"), "--force"])
    assert r.exit_code == 0 and "active: v0002" in r.output
    r = run(app, ["models", "show", "v0002", "--registry", str(tmp_path / "reg"), "--json"])
    assert r.exit_code == 0 and json.loads(r.output)["card"]["activated_by"] == "forced"
    r = run(app, ["models", "rollback", "--registry", str(tmp_path / "reg")])
    assert r.exit_code == 0 and "active: v0001" in r.output


# --- progress and ETA ----------------------------------------------------------------------------------

def test_staged_progress_is_monotonic_and_its_eta_is_the_linear_rest():
    t = [0.0]
    p = StagedProgress({"simulating": 10, "features": 10, "training": 30, "held-out simulation": 5, "report": 250},
                       clock=lambda: t[0])
    seen = []
    for stage, total in (("simulating", 10), ("features", 10), ("training", 1), ("held-out simulation", 5),
                         ("report", 50)):
        for d in range(total + 1):
            t[0] += 1.0
            seen.append(p.update(stage, d, total))
    fr = [f for f, _ in seen]
    assert fr == sorted(fr) and fr[-1] == pytest.approx(1.0) and seen[-1][1] == pytest.approx(0.0)
    f, eta = seen[5]
    assert eta == pytest.approx(6.0 * (1 - f) / f)
    assert sum(p.share.values()) == pytest.approx(1.0)


def test_a_train_retrains_eta_is_exact_when_each_stage_runs_at_its_measured_rate():
    """A shaft-train retrain whose stages take TRAIN_STAGE_SECONDS per unit: the ETA at every step is the time
    really left (the linear ETA is exact when the weights are the true costs); the lumped constants, where a
    train sample costs several lumped ones, would be off by more than half the time left once the simulation
    is done."""
    from rotordiag.models.plant_retrain import retrain_units, stage_seconds

    plant = describe_plant(preset="gen600_4pole")
    units = retrain_units(plant, 40, 2)
    assert units["held-out simulation"] == 6 and units["report"] == 2 * len(report_conditions()) * 6
    assert retrain_units(describe_plant(), 40, 2)["held-out simulation"] == 10
    assert stage_seconds(plant) == TRAIN_STAGE_SECONDS and stage_seconds(describe_plant()) == STAGE_SECONDS
    t = [0.0]
    p = StagedProgress(units, clock=lambda: t[0], seconds=stage_seconds(plant))
    lumped = StagedProgress(units, clock=lambda: t[0])
    total = sum(TRAIN_STAGE_SECONDS[k] * v for k, v in units.items())
    for stage, n in units.items():
        for d in range(1, n + 1):
            t[0] += TRAIN_STAGE_SECONDS[stage]
            f, eta = p.update(stage, d, n)
            assert eta is None or eta == pytest.approx(total - t[0], abs=1e-6)
            if stage == "simulating" and d == n:
                assert abs(lumped.update(stage, d, n)[1] - (total - t[0])) > 0.5 * (total - t[0])


def test_job_eta_is_elapsed_times_the_rest_over_the_fraction():
    from rotordiag.service.api.routes.jobs import eta_seconds

    now = dt.datetime(2026, 1, 1, 12, 0, tzinfo=dt.UTC)
    start = now - dt.timedelta(seconds=60)
    assert eta_seconds("running", 0.25, start, now) == pytest.approx(180.0)
    assert eta_seconds("running", 0.005, start, now) is None
    assert eta_seconds("succeeded", 1.0, start, now) is None
    assert eta_seconds("running", 1.0, start.replace(tzinfo=None), now) == 0.0


def test_job_status_carries_eta_s(tmp_path):
    """A running job's GET /jobs/{id} has `eta_s` (null until 1 % is done, then ≥ 0 and finite)."""
    import threading

    from rotordiag.service.main import create_app

    settings = make_settings(tmp_path)
    app = create_app(settings)
    release = threading.Event()

    def work(params, ctx):
        ctx.progress(0.5, "simulating", "half")
        release.wait(30)
        return {}

    with TestClient(app) as c:
        app.state.rd.jobs.register("retrain", work)
        job = app.state.rd.jobs.submit("retrain", {})
        try:
            from tests.service_util import wait_until

            got = wait_until(lambda: (j := c.get(f"/jobs/{job.id}").json())["progress"] == 0.5 and j,
                             "the job at 50 %", ceiling_s=60)
            assert got["stage"] == "simulating" and got["eta_s"] is not None
            assert math.isfinite(got["eta_s"]) and 0 <= got["eta_s"] < 60
        finally:
            release.set()


# --- end to end ----------------------------------------------------------------------------------------

@pytest.mark.slow
def test_retrain_cli_for_a_preset_stores_its_report_and_shows_it(tmp_path):
    """`rotordiag retrain --preset gen600_4pole` with a few samples: the version is registered with its plant's
    quality report (every condition, both models, not pending) and activated only as that report decides."""
    from rotordiag.cli import app

    reg_root = tmp_path / "reg"
    r = CliRunner().invoke(app, ["retrain", "--registry", str(reg_root), "--preset", "gen600_4pole",
                                 "--n-samples", "24", "--report-cases", "1", "--workers", "0",
                                 "--work-dir", str(tmp_path / "work")])
    assert r.exit_code == 0, r.output
    reg = Registry(reg_root)
    card = reg.card("v0001")
    rep = json.loads((reg_root / "v0001" / "plant_report.json").read_text())
    assert card["plant_report"]["pending"] is False and card["plant"]["name"] == "preset:gen600_4pole"
    assert set(rep["per_condition"]) == {c.name for c in report_conditions()}
    # a shaft train: one held-out case per coupling (rigid, flexible) and one aligned
    assert rep["held_out"]["n_cases"] == 3 and rep["models"]["active"].endswith("(the shipped model)")
    assert rep["held_out"]["plant_model"] == "train"
    for who in ("new", "active"):
        assert 0.0 <= rep["pooled"][who]["macro_f1"] <= 1.0 and rep["pooled"][who]["n"] > 0
    assert (reg.active_version() == "v0001") is (card["plant_report"]["better"] is True)
    assert card["activated_by"] == ("report" if card["plant_report"]["better"] else None)
    shown = CliRunner().invoke(app, ["models", "show", "v0001", "--registry", str(reg_root)])
    assert shown.exit_code == 0 and "quality report for preset:gen600_4pole" in shown.output
    spec = tomllib.loads((tmp_path / "work" / "dataset.toml").read_text())
    assert spec["plant"]["shaftline"] and spec["plant"]["model"] == "train"


@pytest.mark.slow
def test_a_forced_retrain_lists_the_floors_with_the_reports_own_figures(tmp_path):
    """`rotordiag retrain --force` for gen600_4pole with a few samples: the decision stored with the version
    lists each floor, failed exactly when the report's own per-condition figures break it, and the version is
    activated anyway, recorded as forced when the decision said no."""
    from rotordiag.cli import app

    reg_root = tmp_path / "reg"
    r = CliRunner().invoke(app, ["retrain", "--registry", str(reg_root), "--preset", "gen600_4pole", "--n-samples", "24",
                                 "--report-cases", "1", "--workers", "0", "--force", "--work-dir", str(tmp_path / "work")])
    assert r.exit_code == 0, r.output
    reg = Registry(reg_root)
    card = reg.card("v0001")
    rep = json.loads((reg_root / "v0001" / "plant_report.json").read_text())
    d = rep["decision"]
    assert card["plant_report"]["decision"] == d
    fa = [row["new"].get("false_alarm_rate") for row in rep["per_condition"].values()]
    off2 = [row["new"].get("confident_two_bands_off", 0) for row in rep["per_condition"].values()]
    detected = rep["pooled"]["new"].get("moderate_or_worse_detected")
    breaks = {"floor: false alarms": not any(v is not None for v in fa) or any(v is not None and v > 0.05 for v in fa),
              "floor: at most 0 confident": any(k > 0 for k in off2),
              "floor: moderate-or-worse": detected is None or detected < 0.97}
    for head, broken in breaks.items():
        assert any(line.startswith(head) for line in (d["failed"] if broken else d["held"])), (head, d)
    assert d["better"] is (not d["failed"])
    assert reg.active_version() == "v0001"
    assert card["activated_by"] == ("report" if d["better"] else "forced")


@pytest.mark.slow
def test_retrain_request_with_a_shaft_line_runs_on_its_train_and_reports(tmp_path):
    """POST /models/retrain with a shaft line (gen600_4pole's tables, rated 1500 r/min) and a few samples: the job
    simulates its finite-element train, registers the version with the plant's report on train recordings, and
    its status moved through the stages with an ETA."""
    from rotordiag.service.main import create_app
    from rotordiag.simulator.shaftline import PRESETS
    from tests.service_util import wait_until

    tables = {k: v for k, v in PRESETS["gen600_4pole"].items() if k != "rated_speed_rpm"}
    tables["coupling"] = {"type": "flexible"}
    app = create_app(make_settings(tmp_path))
    with TestClient(app) as c:
        r = c.post("/models/retrain", json={"shaftline": tables, "rated_speed_rpm": 1500, "report_cases": 1,
                                            "sweep": {"design": {"n_samples": 20}}}, headers=auth())
        assert r.status_code == 202, r.text
        url, seen = r.json()["url"], []

        def finished():
            j = c.get(url).json()
            seen.append((j["stage"], j["eta_s"]))
            return j["status"] in ("succeeded", "failed") and j

        j = wait_until(finished, "the retrain job", ceiling_s=900, every_s=0.5)
    assert j["status"] == "succeeded", j
    report_file = Path(j["result"]["plant_report"]["file"])
    rep = json.loads(report_file.read_text())
    assert rep["held_out"]["plant_model"] == "train" and rep["held_out"]["n_cases"] == 2    # flexible + aligned
    assert rep["held_out"]["speed_rpm_range"][0] >= 0.8 * 1500 - 1e-6
    assert rep["held_out"]["speed_rpm_range"][1] <= 1.05 * 1500 + 1e-6
    card = json.loads((report_file.parent / "card.json").read_text())
    assert card["plant_report"]["pending"] is False and card["plant"]["shaftline"]["coupling"]["type"] == "flexible"
    assert any(stage == "simulating" for stage, _ in seen)
    etas = [e for _, e in seen if e is not None]
    assert etas and all(math.isfinite(e) and e >= 0 for e in etas)


def test_columns_measured_on_few_plants_are_dropped_before_training():
    """A column seen on 5 of 32 plants (a retrain of 32 gen600_4pole samples had its sub-synchronous peak order so)
    leaves some cross-validation folds all NaN, which the boosted trees cannot bin: dropped; one seen on every
    plant, or on 20 of them, is kept."""
    from rotordiag.models.plant_retrain import drop_unmeasured
    from rotordiag.models.table import FeatureTable

    rng = np.random.default_rng(0)
    pid = np.repeat(np.arange(32), 3)
    X = rng.normal(size=(96, 4))
    X[pid >= 5, 1] = np.nan       # measured on plants 0-4 only
    X[pid >= 20, 2] = np.nan      # measured on 20 plants
    X[:, 3] = np.nan              # never measured
    t = FeatureTable(X, ["a", "few", "twenty", "never"], rng.uniform(0, 0.5, 96), pid,
                     np.array(["rigid"] * 96, dtype=object), np.full(96, 1500.0), np.arange(96), {})
    kept, dropped = drop_unmeasured(t)
    assert dropped == ["few", "never"] and list(kept.feature_names) == ["a", "twenty"]


def test_retrain_request_takes_the_shaftline_files_text_with_its_rated_speed(tmp_path):
    """POST /models/retrain's `shaftline_toml`: the file `rotordiag retrain --shaftline` reads, rated speed
    included, gives the same plant and the sweep around that speed; bad text is a 422 saying so."""
    from rotordiag.service.errors import InputError
    from rotordiag.service.schemas import RetrainRequest
    from rotordiag.service.work import prepare_retrain_job
    from rotordiag.simulator import shaftline
    from rotordiag.simulator.dataset.spec import parse_spec
    from rotordiag.simulator.train.plant import TrainPlant

    text = "rated_speed_rpm = 3600\n" + EXAMPLE.read_text()
    params = prepare_retrain_job(RetrainRequest.model_validate({"shaftline_toml": text}), make_settings(tmp_path))
    resolved = parse_spec(params["spec_toml"])
    assert resolved.spec.plant.model == "train"
    assert resolved.base_plant == TrainPlant.of(shaftline.ShaftLine.from_file(EXAMPLE))
    sp = resolved.spec.operating.speed_rpm
    assert (sp.min, sp.max) == (pytest.approx(0.8 * 3600), pytest.approx(1.05 * 3600))
    assert params["plant_description"]["rated_speed_rpm"] == [3600.0] and params["activate"] is True
    with pytest.raises(InputError, match="not valid TOML"):
        prepare_retrain_job(RetrainRequest.model_validate({"shaftline_toml": "[generator"}), make_settings(tmp_path))
    # plant values over a shaft line are the train's (TRAIN_PERTURBABLE); a lumped field is named as unknown
    params = prepare_retrain_job(RetrainRequest.model_validate({"shaftline_toml": text, "plant": {
        "clearance_m": 3.1e-4}}), make_settings(tmp_path))
    assert parse_spec(params["spec_toml"]).base_plant.clearance_m == pytest.approx(3.1e-4)
    with pytest.raises(InputError, match="generator_mass_kg"):
        prepare_retrain_job(RetrainRequest.model_validate({"shaftline_toml": text, "plant": {
            "generator_mass_kg": 1.0}}), make_settings(tmp_path))
    with pytest.raises(InputError, match="once"):
        prepare_retrain_job(RetrainRequest.model_validate({"shaftline_toml": text, "shaftline": {}}),
                            make_settings(tmp_path))


def test_retrain_cli_refuses_a_work_folder_whose_dataset_it_cannot_resume(tmp_path):
    """A work folder holding a dataset.h5 this retrain cannot resume (another spec, or not a dataset at all) is a
    clear exit 2 naming --work-dir, not a traceback; nothing is registered."""
    from rotordiag.cli import app

    work = tmp_path / "work"
    work.mkdir()
    (work / "dataset.h5").write_bytes(b"not an HDF5 file")
    reg_root = tmp_path / "reg"
    r = CliRunner().invoke(app, ["retrain", "--registry", str(reg_root), "--preset", "gen600_4pole",
                                 "--n-samples", "24", "--report-cases", "1", "--workers", "0",
                                 "--work-dir", str(work)])
    assert r.exit_code == 2, r.output
    assert "--work-dir" in r.output and "dataset.h5" in r.output and "Traceback" not in r.output
    assert r.exception is None or isinstance(r.exception, SystemExit)
    assert not (reg_root / "v0001").exists()
