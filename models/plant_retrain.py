"""Retraining for one plant, and the quality report that says whether the new model is better *for that plant*.

The flow (``rotordiag retrain``, ``POST /models/retrain``; docs/models.md, "Retraining for one plant"):

1. :func:`describe_plant` — the plant as the user gives it (a preset name or shaft-line tables, its rated
   speeds, Plant-field overrides);
2. :func:`plant_dataset_spec` — the one place that turns that description into a dataset spec: the plant's
   geometry within manufacturing tolerances (:data:`PLANT_TOLERANCES`), its rated and off-rated speeds, the
   training data's probe layout and measurement realities;
3. the dataset, features and model (``models.train.train_and_register``, registered *not* active, its card
   marked ``plant_report.pending`` so that nothing activates it before its report);
4. :func:`held_out_cases` / :func:`simulate_held_out` — recordings of the same plant drawn with a seed stream
   no training spec uses, measured under every condition of :mod:`models.robustness` that is about the
   measurement (not another plant), and :func:`quality_report` — the new model and the active one diagnosed on
   those same recordings, with paired bootstrap intervals;
5. :func:`decide` — "better" as docs/models.md defines it; :func:`finish_retrain` stores the report with the
   version and activates it only when it is better, or when the user forces it (card ``activated_by``).
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

#: Relative half-widths (uniform ×(1 ± r)) of the lumped plant's fields around the described plant: what
#: manufacturing tolerances, the oil's temperature and wear move on one machine. Used by the training spec
#: (``plant.perturb``) and by the report's held-out plants alike, so that both are draws of the same machine.
PLANT_TOLERANCES: dict[str, float] = {
    "journal1_mass_kg": 0.03, "generator_mass_kg": 0.03, "journal3_mass_kg": 0.03, "journal4_mass_kg": 0.03,
    "exciter_mass_kg": 0.03, "journal6_mass_kg": 0.03,
    "generator_stiffness_n_m": 0.05, "exciter_stiffness_n_m": 0.05,
    "generator_damping_n_s_m": 0.2, "exciter_damping_n_s_m": 0.2,
    "asymmetry": 0.1, "clearance_m": 0.1, "viscosity_pa_s": 0.2,
    "bearing_radius_m": 0.01, "bearing_length_m": 0.02, "coupling_stiffness_n_m": 0.3,
}

#: Relative half-widths (uniform ×(1 ± r)) of a shaft train's values (``simulator.train.plant.TRAIN_PERTURBABLE``)
#: around the described plant, for its training spec and its held-out recordings alike (docs/models.md, "Retraining
#: for one plant"): what a manufacturer states for one machine — spans, diameters, overhangs ±1 %, bearing bores
#: ±0.5 % and lengths ±1 %, body masses ±2 % — and what moves on the running machine: the clearance ±15 % (machining
#: and wear), the oil's viscosity ±30 % (oil inlet temperature ±5 K on an ISO VG 32/46 oil), the coupling's
#: stiffnesses ±30 %, ρ ±10 %, the damping ±20 % and the balance grade ±60 % (G1–G4 around G2.5).
TRAIN_TOLERANCES: dict[str, float] = {
    "generator_span_m": 0.01, "exciter_span_m": 0.01, "generator_diameter_m": 0.01, "exciter_diameter_m": 0.01,
    "generator_body_mass_kg": 0.02, "exciter_body_mass_kg": 0.02, "overhang_m": 0.01,
    "bearing_diameter_m": 0.005, "bearing_length_m": 0.01, "clearance_m": 0.15, "viscosity_pa_s": 0.3,
    "coupling_stiffness_n_m": 0.3, "coupling_angular_stiffness_n_m_rad": 0.3, "generator_asymmetry": 0.1,
    "damping_ratio": 0.2, "balance_grade_mm_s": 0.6,
}
#: Couplings of a shaft train's samples (``simulator.dataset.spec.TRAIN_MECHANISMS``) when the shaft line does not
#: name its own ``coupling.type``
TRAIN_COUPLINGS = ("rigid", "flexible")
#: Half-range of a train sample's angular offset at the coupling (mrad), as models/trains/*.toml
ANGULAR_OFFSET_MRAD = 0.04

#: The default sweep's speed range as fractions of the rated speed(s): run-up, slow-down and off-rated running.
SPEED_FRACTIONS = (0.8, 1.05)
#: Δ levels of the default sweep: a quarter of the samples aligned (Δ = 0), the rest spread over 0.01–0.6
#: (a Sobol design maps a list onto equally likely levels)
MISALIGNMENT_LEVELS: list[float] = [0.0] * 16 + [round(float(x), 4) for x in np.linspace(0.01, 0.6, 48)]
#: Default number of simulated samples of a plant's dataset: the largest size of the measured learning curve
#: (docs/models.md, "Learning curve (gen600_4pole, shaft trains)": about 3 min of idle 2-core time on a train)
DEFAULT_N_SAMPLES = 192

#: The default sweep: the shipped training data's operating ranges, mechanisms and measurement realities
#: (models/default/dataset_*.toml), the speed following the plant's rated speed (:func:`plant_dataset_spec`).
PLANT_SWEEP: dict[str, Any] = {
    "design": {"method": "sobol", "n_samples": DEFAULT_N_SAMPLES, "seed": 0},
    "operating": {
        "misalignment": MISALIGNMENT_LEVELS,
        "speed_rpm": {"min": 1200.0, "max": 2200.0},
        "unbalance": {"min": 0.02, "max": 0.10},
        "unbalance_phase_rad": {"min": 0.0, "max": 2 * math.pi},
        "exciter_unbalance": {"min": 0.0, "max": 0.05},
        "exciter_unbalance_phase_rad": {"min": 0.0, "max": 2 * math.pi},
        "offset_angle_rad": {"min": 0.0, "max": 2 * math.pi},
        "coupling_phase_rad": {"min": 0.0, "max": 2 * math.pi},
        "mechanism": {"pin": 0.25, "rigid": 0.25, "offset": 0.25, "flexible": 0.25},
    },
    "plant": {"perturb": dict(PLANT_TOLERANCES)},
    "measurement": {
        "bearings": [1, 2, 3, 4], "probe_angles_deg": [45.0, 135.0], "sample_rate_hz": 2560.0,
        "duration_revs": 48, "snr_db": {"min": 10.0, "max": 45.0}, "runout_1x_um": {"min": 0.0, "max": 6.0},
        "runout_2x_um": {"min": 0.0, "max": 2.0}, "speed_fluctuation": 0.002, "speed_fluctuation_hz": 0.5,
    },
    "simulation": {"transient_revs": 400, "samples_per_rev": 128, "record_revs_min": 48, "classify_motion": False},
}

#: The sweep of a plant given as a shaft line (preset or the user's tables): its finite-element train
#: (``[plant] model = "train"``), misaligned by moving the exciter's bearings by Δ·c in any direction with a small
#: angular offset, the generator unbalanced to its balance grade, the measurement realities of models/trains/*.toml;
#: the couplings, speeds and instrumented bearings follow the plant (:func:`plant_dataset_spec`).
TRAIN_SWEEP: dict[str, Any] = {
    "design": {"method": "sobol", "n_samples": DEFAULT_N_SAMPLES, "seed": 0},
    "operating": {
        "misalignment": MISALIGNMENT_LEVELS,
        "speed_rpm": {"min": 1200.0, "max": 2200.0},
        "unbalance_phase_rad": {"min": 0.0, "max": 2 * math.pi},
        "offset_angle_rad": {"min": 0.0, "max": 2 * math.pi},
        "angular_misalignment_mrad": {"min": -ANGULAR_OFFSET_MRAD, "max": ANGULAR_OFFSET_MRAD},
        "mechanism": list(TRAIN_COUPLINGS),
    },
    "plant": {"model": "train", "perturb": dict(TRAIN_TOLERANCES)},
    "measurement": {
        "bearings": [1, 2, 3, 4], "probe_angles_deg": [45.0, 135.0], "sample_rate_hz": 2560.0,
        "duration_revs": 32, "snr_db": {"min": 10.0, "max": 45.0}, "runout_1x_um": {"min": 0.0, "max": 6.0},
        "runout_2x_um": {"min": 0.0, "max": 2.0}, "speed_fluctuation": 0.002, "speed_fluctuation_hz": 0.5,
    },
    "simulation": {"transient_revs": 100, "samples_per_rev": 128, "record_revs_min": 32, "classify_motion": False},
}

#: The report's held-out recordings come from this seed stream (``numpy.random.default_rng([REPORT_STREAM,
#: seed])``); training specs draw from Sobol sequences scrambled with their own seed, never from it.
REPORT_STREAM = 48_003
#: Default held-out cases per class (each mechanism and aligned) of a report
DEFAULT_REPORT_CASES = 6
#: Bootstrap draws and level of the report's intervals
BOOTSTRAP_DRAWS, BOOTSTRAP_LEVEL = 1000, 0.90

#: Floors a plant-retrained model must reach on its plant's report before it is activated automatically, whatever
#: the active model scores (:func:`decide`; docs/models.md, "Activated only if better"): the issue's per-condition
#: targets. Under every measurement condition at most this share of the healthy machines is given any
#: misalignment class (any status) — with fewer than 20 healthy machines per condition, none ...
FLOOR_FALSE_ALARM_RATE = 0.05
#: ... and at most this many confident verdicts two or more bands off the true band, under any condition ...
FLOOR_CONFIDENT_TWO_BANDS_OFF = 0
#: ... and, pooled over the conditions, at least this share of the moderate-or-worse machines (Δ ≥ the second band
#: edge, 0.15) given slight or worse (model class, any status): the issue's held-out detection target
FLOOR_DETECTION_RATE = 0.97


@dataclass(frozen=True)
class PlantDescription:
    """One plant to retrain for.

    ``shaftline``: the shaft-line tables (``simulator.shaftline.ShaftLine.from_dict``); ``rated_speed_rpm``: its
    rated speed(s) (empty: the sweep's default range); ``plant_set``: ``simulator.Plant`` fields set over the
    reduced plant; ``name``: what the card calls it (``preset:gen600_4pole``, ``shaftline:plant.toml``).
    """

    name: str
    shaftline: dict[str, Any] | None
    rated_speed_rpm: tuple[float, ...] = ()
    plant_set: dict[str, Any] = field(default_factory=dict)

    def base_plant(self):
        """The plant its samples are drawn around: the ``TrainPlant`` of its shaft line (:meth:`base_train`), or
        MODEL.md's lumped ``simulator.Plant`` when it has none; ``plant_set`` applied."""
        from rotordiag.simulator import Plant

        if self.is_train:
            return self.base_train()
        base = Plant.default()
        return base.replace(**self.plant_set) if self.plant_set else base

    @property
    def is_train(self) -> bool:
        """Whether this plant is retrained for on its finite-element shaft train (it has a shaft line); the
        "default" plant (MODEL.md's, no shaft line) stays the paper's lumped model."""
        return self.shaftline is not None

    def base_train(self):
        """The ``simulator.train.plant.TrainPlant`` of the shaft line, ``plant_set`` (train values) applied."""
        from rotordiag.simulator.shaftline import ShaftLine
        from rotordiag.simulator.train.plant import TrainPlant

        if self.shaftline is None:
            raise ValueError("the default plant has no shaft line: it is the paper's lumped plant")
        base = TrainPlant.of(ShaftLine.from_dict(self.shaftline))
        return base.replace(**self.plant_set) if self.plant_set else base

    def couplings(self) -> tuple[str, ...]:
        """The couplings its samples have: the one its shaft line names (``coupling.type``), else rigid and
        flexible (:data:`TRAIN_COUPLINGS`)."""
        named = ((self.shaftline or {}).get("coupling") or {}).get("type")
        return (str(named),) if named in TRAIN_COUPLINGS else TRAIN_COUPLINGS

    def speed_range_rpm(self) -> tuple[float, float] | None:
        """(min, max) r/min of the default sweep: :data:`SPEED_FRACTIONS` of the rated speed(s)."""
        if not self.rated_speed_rpm:
            return None
        return (max(100.0, SPEED_FRACTIONS[0] * min(self.rated_speed_rpm)),
                min(6000.0, SPEED_FRACTIONS[1] * max(self.rated_speed_rpm)))

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "rated_speed_rpm": list(self.rated_speed_rpm), "plant_set": dict(self.plant_set),
                "shaftline": self.shaftline}


def describe_plant(*, preset: str | None = None, shaftline: Mapping[str, Any] | str | Path | None = None,
                   rated_speed_rpm: float | Sequence[float] | None = None,
                   plant_set: Mapping[str, Any] | None = None) -> PlantDescription:
    """The plant from a preset name, shaft-line tables or a shaft-line TOML file (exactly one of them, or
    neither: MODEL.md's plant), its rated speed(s) (a preset gives its own) and Plant-field overrides.

    Raises
    ------
    ValueError
        Both or an unknown preset, an unreadable or invalid shaft line (the message names the key).
    """
    from rotordiag.simulator.shaftline import PRESETS, ShaftLine, to_plant

    if preset is not None and shaftline is not None:
        raise ValueError("preset and shaftline: give the plant one way, a preset name or the shaft-line tables")
    rated: tuple[float, ...] = ()
    if rated_speed_rpm is not None:
        rated = tuple(float(v) for v in ([rated_speed_rpm] if isinstance(rated_speed_rpm, (int, float))
                                         else rated_speed_rpm))
        if not rated or any(not (math.isfinite(v) and 100.0 <= v <= 6000.0) for v in rated):
            raise ValueError(f"rated_speed_rpm: {list(rated)} — give speeds of 100–6000 r/min")
    if preset is not None:
        if preset not in PRESETS:
            raise ValueError(f"preset {preset!r} is not known; the presets: {', '.join(sorted(PRESETS))}")
        tables = {k: v for k, v in PRESETS[preset].items() if k != "rated_speed_rpm"}
        desc = PlantDescription(f"preset:{preset}", tables,
                                rated or tuple(float(v) for v in PRESETS[preset]["rated_speed_rpm"]),
                                dict(plant_set or {}))
    elif isinstance(shaftline, (str, Path)):
        import tomllib

        path = Path(shaftline)
        try:
            tables = tomllib.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError) as exc:
            raise ValueError(f"shaftline {path}: cannot be read ({exc})") from None
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"shaftline {path}: not valid TOML ({exc})") from None
        file_rated = tables.pop("rated_speed_rpm", None)
        if not rated and file_rated is not None:
            return replace(describe_plant(shaftline=tables, rated_speed_rpm=file_rated, plant_set=plant_set),
                           name=f"shaftline:{path.name}")
        desc = PlantDescription(f"shaftline:{path.name}", tables, rated, dict(plant_set or {}))
    elif shaftline is not None:
        tables = dict(shaftline)
        file_rated = tables.pop("rated_speed_rpm", None)
        if not rated and file_rated is not None:
            return describe_plant(shaftline=tables, rated_speed_rpm=file_rated, plant_set=plant_set)
        desc = PlantDescription("shaftline:inline", tables, rated, dict(plant_set or {}))
    else:
        desc = PlantDescription("default", None, rated, dict(plant_set or {}))
    if desc.shaftline is not None:
        try:
            to_plant(ShaftLine.from_dict(desc.shaftline))
        except (TypeError, ValueError, OverflowError, ZeroDivisionError, FloatingPointError) as exc:
            raise ValueError(f"shaftline: {exc}") from None
    try:
        desc.base_plant()
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"plant: {exc}") from None
    return desc


def plant_dataset_spec(plant: PlantDescription, *, n_samples: int | None = None, seed: int | None = None,
                       sweep: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The dataset spec (as tables) of ``plant``: the one function every retraining path builds its data with.

    :data:`PLANT_SWEEP` with the speed at :data:`SPEED_FRACTIONS` of the rated speed(s), the plant's shaft line
    (or MODEL.md's plant) with ``plant_set`` over it and :data:`PLANT_TOLERANCES` around it; ``sweep`` (tables of
    a spec) overrides what it names (a mechanism table is replaced whole), then ``n_samples`` and ``seed``.
    """
    from rotordiag.core.tables import deep_merge

    defaults: dict[str, Any] = PLANT_SWEEP
    if plant.is_train:
        n_bearings = plant.base_train().n_bearings
        defaults = deep_merge(TRAIN_SWEEP, {"operating": {"mechanism": list(plant.couplings())},
                                            "measurement": {"bearings": list(range(1, n_bearings + 1))}},
                              whole=("mechanism", "bearings"))
    rng = plant.speed_range_rpm()
    if rng is not None:
        defaults = deep_merge(defaults, {"operating": {"speed_rpm": {"min": rng[0], "max": rng[1]}}})
    spec = deep_merge(defaults, dict(sweep or {}), whole=("mechanism", "misalignment"))
    if n_samples is not None:
        spec["design"]["n_samples"] = int(n_samples)
    if seed is not None:
        spec["design"]["seed"] = int(seed)
    spec.setdefault("plant", {})
    if plant.plant_set:
        spec["plant"]["set"] = dict(plant.plant_set)
    if plant.shaftline is not None:
        spec["plant"]["shaftline"] = plant.shaftline
    return spec


#: What a plant's retraining lays over the shipped recipe: the offset-direction and angular-offset heads
#: (``models.direction``), which its dataset's labels (``offset_angle_rad``, ``angular_misalignment_mrad``) teach
PLANT_TRAINING: dict[str, Any] = {"direction": {"heads": True}}


def plant_train_config(overrides: Mapping[str, Any] | None = None) -> Any:
    """The training configuration of a plant's model: the shipped recipe (``TrainConfig.shipped``) with
    :data:`PLANT_TRAINING`, then ``overrides`` (train.toml tables) over both."""
    from rotordiag.core.tables import deep_merge

    from .config import TrainConfig

    return TrainConfig.shipped(deep_merge(PLANT_TRAINING, dict(overrides or {})))


# ----------------------------------------------------------------------------- held-out recordings
def held_out_cases(plant: PlantDescription, n_per_class: int, seed: int) -> list[dict]:
    """Held-out cases of ``plant`` in :func:`models.robustness.design`'s form: ``n_per_class`` for each of
    :data:`models.robustness.MECHANISMS` and as many aligned, each a draw of the plant within
    :data:`PLANT_TOLERANCES`, half at a rated speed (±1 %) and half anywhere in the sweep's speed range, Δ
    uniform in 0.02–0.6, from the seed stream :data:`REPORT_STREAM` (no training spec draws from it)."""
    if plant.is_train:
        return _held_out_train_cases(plant, n_per_class, seed)
    from .robustness import MECHANISMS

    rng = np.random.default_rng([REPORT_STREAM, int(seed)])
    base = plant.base_plant().to_dict()
    lo, hi = plant.speed_range_rpm() or (1200.0, 2200.0)
    rated = plant.rated_speed_rpm or (0.5 * (lo + hi),)
    cases = []
    for i, mech in enumerate([m for m in MECHANISMS for _ in range(n_per_class)] + ["aligned"] * n_per_class):
        p, speed = _draw_case_plant(base, PLANT_TOLERANCES, i, rated, (lo, hi), rng)
        cases.append(dict(
            plant=p, speed_rpm=speed, misalignment=0.0 if mech == "aligned" else float(rng.uniform(0.02, 0.6)),
            mechanism="pin" if mech == "aligned" else mech, label_mechanism=mech,
            unbalance=float(rng.uniform(0.02, 0.1)), unbalance_phase_rad=float(rng.uniform(0, 2 * math.pi)),
            exciter_unbalance=float(rng.uniform(0, 0.05)), exciter_unbalance_phase_rad=float(rng.uniform(0, 2 * math.pi)),
            offset_angle_rad=float(rng.uniform(0, 2 * math.pi)), coupling_phase_rad=float(rng.uniform(0, 2 * math.pi)),
        ))
    return cases


def _draw_case_plant(base: dict, tolerances: Mapping[str, float], i: int, rated: Sequence[float],
                     speed_range: tuple[float, float], rng: np.random.Generator) -> tuple[dict, float]:
    """One held-out case's plant (each toleranced value × (1 + u), u uniform in ±its tolerance, lists element by
    element) and its speed: even cases at a rated speed ±1 %, odd ones anywhere in ``speed_range``."""
    p = dict(base)
    for name, r in tolerances.items():
        v = p[name]
        p[name] = ([float(x) * (1 + r * rng.uniform(-1, 1)) for x in v] if isinstance(v, list)
                   else float(v) * (1 + r * rng.uniform(-1, 1)))
    speed = (float(rng.choice(rated)) * float(rng.uniform(0.99, 1.01)) if i % 2 == 0
             else float(rng.uniform(*speed_range)))
    return p, speed


def _held_out_train_cases(plant: PlantDescription, n_per_class: int, seed: int) -> list[dict]:
    """:func:`held_out_cases` of a shaft-train plant: ``n_per_class`` per coupling of :meth:`PlantDescription.couplings`
    and as many aligned, each a draw of the train within :data:`TRAIN_TOLERANCES`, half at a rated speed (±1 %) and
    half anywhere in the sweep's range, Δ uniform in 0.02–0.6 in a uniform direction, angular offset uniform in
    ±:data:`ANGULAR_OFFSET_MRAD` (0 for the aligned), from the seed stream :data:`REPORT_STREAM`."""
    rng = np.random.default_rng([REPORT_STREAM, int(seed)])
    base = plant.base_train().to_dict()
    lo, hi = plant.speed_range_rpm() or (1200.0, 2200.0)
    rated = plant.rated_speed_rpm or (0.5 * (lo + hi),)
    couplings = plant.couplings()
    cases = []
    for i, mech in enumerate([m for m in couplings for _ in range(n_per_class)] + ["aligned"] * n_per_class):
        p, speed = _draw_case_plant(base, TRAIN_TOLERANCES, i, rated, (lo, hi), rng)
        aligned = mech == "aligned"
        cases.append(dict(
            plant=p, speed_rpm=speed, misalignment=0.0 if aligned else float(rng.uniform(0.02, 0.6)),
            mechanism=couplings[i % len(couplings)] if aligned else mech, label_mechanism=mech,
            angular_misalignment_mrad=0.0 if aligned else float(rng.uniform(-ANGULAR_OFFSET_MRAD, ANGULAR_OFFSET_MRAD)),
            unbalance_phase_rad=float(rng.uniform(0, 2 * math.pi)), offset_angle_rad=float(rng.uniform(0, 2 * math.pi)),
        ))
    return cases


def simulate_train_case(c: dict, revs: int) -> np.ndarray | None:
    """One shaft-train case of :func:`held_out_cases`: its journal displacements in m (n, bearings, 2) over
    ``revs`` + 3 revolutions after the training sweep's transient, from its static state, built exactly as a
    training sample (``simulator.dataset.worker.sample_train``); None when the run did not finish ``ok``.
    Raises ``ValueError`` when the simulator refuses the train (a journal outside its clearance)."""
    from rotordiag.simulator.dataset.design import SampleParams
    from rotordiag.simulator.dataset.worker import sample_train
    from rotordiag.simulator.train.dynamics import simulate_train
    from rotordiag.simulator.train.plant import TrainPlant

    from .robustness import SAMPLES_PER_REV

    sim = TRAIN_SWEEP["simulation"]
    params = SampleParams(index=0, plant=c["plant"], speed_rpm=c["speed_rpm"], misalignment=c["misalignment"],
                          unbalance=0.0, unbalance_phase_rad=c["unbalance_phase_rad"], exciter_unbalance=0.0,
                          exciter_unbalance_phase_rad=0.0, offset_angle_rad=c["offset_angle_rad"],
                          mechanism=c["mechanism"], sample_seed=0,
                          angular_misalignment_mrad=c["angular_misalignment_mrad"])
    train = sample_train(TrainPlant.from_dict(c["plant"]), params)
    run = simulate_train(train, c["speed_rpm"], transient_revs=sim["transient_revs"], record_revs=revs + 3,
                         samples_per_rev=SAMPLES_PER_REV)
    return run.journal_m.astype(np.float32) if run.status == "ok" else None


def report_conditions() -> tuple[Any, ...]:
    """The :data:`models.robustness.CONDITIONS` of a plant's report: every one measured on the plant's own
    recordings (those of another simulated set — the presets, the far plants — are about other plants)."""
    from .robustness import CONDITIONS

    return tuple(c for c in CONDITIONS if c.sim_set == "base")


def simulate_held_out(cases: list[dict], *, progress: Callable[[int, int], None] | None = None,
                      cache: Path | None = None) -> list[np.ndarray | None]:
    """Journal displacements of each case over the longest record a report condition takes (None: the run
    failed or the simulator refused the plant); ``cache``: an ``.npz`` read when present, else written."""
    from .robustness import simulate_case

    def one(c: dict, revs: int) -> np.ndarray | None:
        return simulate_train_case(c, revs) if c["plant"].get("model") == "train" else simulate_case(c, revs)

    if cache is not None and cache.is_file():
        z = np.load(cache, allow_pickle=False)
        return [z[f"d{i}"] if f"d{i}" in z.files else None for i in range(len(cases))]
    revs = max(c.revs for c in report_conditions())
    out: list[np.ndarray | None] = []
    for i, c in enumerate(cases):
        try:
            out.append(one(c, revs))
        except ValueError:
            out.append(None)
        if progress is not None:
            progress(i + 1, len(cases))
    if cache is not None:
        cache.parent.mkdir(parents=True, exist_ok=True)
        arrays: dict[str, Any] = {f"d{i}": d for i, d in enumerate(out) if d is not None}
        np.savez(cache, **arrays)
    return out


# ----------------------------------------------------------------------------- the report
def _scored(outs: list) -> list:
    return [o for o in outs if o.status not in ("sim failed", "refused")]


def _figures(outs: list, names: list[str], edges: np.ndarray) -> dict[str, Any]:
    """Band macro-F1 (over the bands present in the truth), false alarms, confident share, confident two-bands-off,
    90 % coverage and the share flagged out of distribution of one model's outcomes (refused and failed runs
    counted, not scored)."""
    from sklearn.metrics import f1_score

    s = _scored(outs)
    n = len(s)
    if not n:
        return {"n": 0, "refused": len(outs)}
    truth = np.searchsorted(edges, [o.delta for o in s], side="right")
    pred = np.array([names.index(o.model_class) for o in s])
    aligned = np.array([o.mechanism == "aligned" for o in s])
    conf = np.array([o.status == "confident" and o.severity in names for o in s])
    shown = np.array([names.index(o.severity) if o.severity in names else -9 for o in s])
    lo = np.array([o.interval[0] for o in s])
    hi = np.array([o.interval[1] for o in s])
    delta = np.array([o.delta for o in s])
    has = np.isfinite(lo) & np.isfinite(hi)
    est = np.array([o.delta_model for o in s], dtype=float)
    ok = np.isfinite(est)
    worse = truth >= 2                  # moderate or worse: Δ at or above the second band edge
    return {
        "n": n, "refused": len(outs) - n,
        "macro_f1": float(f1_score(truth, pred, labels=np.unique(truth), average="macro", zero_division=0)),
        "false_alarms": int(np.sum(aligned & (pred != 0))), "n_aligned": int(aligned.sum()),
        "false_alarm_rate": float(np.mean(pred[aligned] != 0)) if aligned.any() else None,
        "confident_share": float(conf.mean()),
        "ood_share": float(np.mean([o.ood for o in s])),
        "confident_two_bands_off": int(np.sum(conf & (np.abs(shown - truth) >= 2))),
        "interval_coverage": float(np.mean((lo[has] <= delta[has]) & (delta[has] <= hi[has]))) if has.any() else None,
        "spearman_delta": _spearman(est[ok], delta[ok]),
        "n_moderate_or_worse": int(worse.sum()),
        "moderate_or_worse_detected": float(np.mean(pred[worse] >= 1)) if worse.any() else None,
        **_direction_figures(s, conf),
    }


#: a direction is right when within this many degrees of the true one
DIRECTION_TOLERANCE_DEG = 45.0
#: the confident answers whose direction the report scores apart: true Δ at least this (moderate or worse)
DIRECTION_MIN_DELTA = 0.15


def _direction_figures(s: list, conf: np.ndarray) -> dict[str, Any]:
    """Direction accuracy of scored outcomes ``s`` (``conf``: which are confident answers) on the misaligned
    recordings whose features carry DC positions and whose case has a true direction: the share whose given
    direction is within :data:`DIRECTION_TOLERANCE_DEG` of the true one (no direction given counts as not right),
    the same among confident answers with true Δ ≥ :data:`DIRECTION_MIN_DELTA`, each with its Wilson interval and
    n; the share of those recordings given a direction, the share right among them and the share whose true
    direction lies within the answer's calibrated 90 % arc; and the angular offset's
    90 % interval coverage, mean absolute error and Spearman correlation with the true α where α was given. ``direction_estimated`` False (every figure None): the model gave no direction
    on any recording (a model without direction heads)."""
    from .direction import angle_error_deg

    given = np.array([np.isfinite(o.direction_deg) for o in s], dtype=bool)
    ang = np.array([np.isfinite(o.angular_mrad) for o in s], dtype=bool)
    out: dict[str, Any] = {"direction_estimated": bool(given.any() or ang.any()
                                                        or any(o.direction_code not in ("", "model_without_direction")
                                                               for o in s))}
    keys = ("direction_n", "direction_accuracy", "direction_accuracy_interval", "direction_given_share",
            "direction_accuracy_given", "direction_interval_coverage", "direction_confident_n", "direction_accuracy_confident",
            "direction_accuracy_confident_interval", "angular_n", "angular_coverage", "angular_mae_mrad",
            "angular_spearman")
    if not out["direction_estimated"]:
        return {**out, **dict.fromkeys(keys)}
    scope = np.array([o.delta > 0 and o.dc_available and np.isfinite(o.true_angle_rad) for o in s], dtype=bool)
    right = np.array([bool(g) and angle_error_deg(o.direction_deg, o.true_angle_rad) <= DIRECTION_TOLERANCE_DEG
                      for o, g in zip(s, given)], dtype=bool)
    strong = scope & conf & np.array([o.delta >= DIRECTION_MIN_DELTA for o in s], dtype=bool)
    n, k = int(scope.sum()), int((right & scope).sum())
    nc, kc = int(strong.sum()), int((right & strong).sum())
    out.update({"direction_n": n, "direction_accuracy": k / n if n else None,
                "direction_accuracy_interval": _wilson(k, n), "direction_given_share": float(given[scope].mean()) if n
                else None, "direction_accuracy_given": k / int((given & scope).sum()) if (given & scope).any() else None,
                "direction_interval_coverage": float(np.mean([
                    angle_error_deg(o.direction_deg, o.true_angle_rad) <= o.direction_halfwidth_deg
                    for o, g in zip(s, given & scope) if g])) if (given & scope).any() else None,
                "direction_confident_n": nc, "direction_accuracy_confident": kc / nc if nc else None,
                "direction_accuracy_confident_interval": _wilson(kc, nc)})
    a_scope = ang & np.array([np.isfinite(o.true_angular_mrad) for o in s], dtype=bool)
    na = int(a_scope.sum())
    if na:
        t = np.array([o.true_angular_mrad for o in s])[a_scope]
        e = np.array([o.angular_mrad for o in s])[a_scope]
        lo_a = np.array([o.angular_interval[0] for o in s])[a_scope]
        hi_a = np.array([o.angular_interval[1] for o in s])[a_scope]
        out.update({"angular_n": na, "angular_coverage": float(np.mean((lo_a <= t) & (t <= hi_a))),
                    "angular_mae_mrad": float(np.mean(np.abs(e - t))), "angular_spearman": _spearman(e, t)})
    else:
        out.update({"angular_n": 0, "angular_coverage": None, "angular_mae_mrad": None, "angular_spearman": None})
    return out


def _spearman(a: np.ndarray, b: np.ndarray) -> float | None:
    """Spearman rank correlation of the estimated and true Δ (None with fewer than 3 pairs or a constant side)."""
    from scipy.stats import spearmanr

    if a.size < 3 or np.ptp(a) == 0 or np.ptp(b) == 0:
        return None
    return float(spearmanr(a, b).statistic)


def _wilson(k: int, n: int) -> list[float] | None:
    from scipy.stats import binomtest

    if n <= 0:
        return None
    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=BOOTSTRAP_LEVEL, method="wilson")
    return [float(ci.low), float(ci.high)]


def _pooled_arrays(outs_by_cond: dict[str, list], names: list[str], edges: np.ndarray):
    """(case index, true band, predicted band, aligned, confident two-bands-off) of every scored outcome
    over the conditions, and the mechanism of each case (for stratified resampling)."""
    case, truth, pred, aligned = [], [], [], []
    for outs in outs_by_cond.values():
        for i, o in enumerate(outs):
            if o.status in ("sim failed", "refused"):
                continue
            case.append(i)
            truth.append(int(np.searchsorted(edges, o.delta, side="right")))
            pred.append(names.index(o.model_class))
            aligned.append(o.mechanism == "aligned")
    return np.array(case, int), np.array(truth, int), np.array(pred, int), np.array(aligned, bool)


def paired_bootstrap(new: dict[str, list], old: dict[str, list], names: list[str], edges: np.ndarray,
                     mechanisms: list[str], *, draws: int = BOOTSTRAP_DRAWS, level: float = BOOTSTRAP_LEVEL,
                     seed: int = 0) -> dict[str, Any]:
    """Intervals of new − old macro-F1 and false-alarm rate pooled over every condition, resampling the
    held-out *cases* (each with all its conditions' recordings, for both models together) within each class.

    Returns ``{"macro_f1_diff": [lo, hi], "false_alarm_diff": [lo, hi], "macro_f1_diff_point": .., ...}``.
    """
    from sklearn.metrics import f1_score

    a = _pooled_arrays(new, names, edges)
    b = _pooled_arrays(old, names, edges)
    n_cases = len(mechanisms)
    strata: dict[str, list[int]] = {}
    for i, m in enumerate(mechanisms):
        strata.setdefault(m, []).append(i)

    def stats(weights: np.ndarray) -> tuple[float, float]:
        out = []
        for case, truth, pred, aligned in (a, b):
            w = weights[case]
            f1 = f1_score(truth, pred, labels=np.unique(truth[w > 0]), average="macro", sample_weight=w,
                          zero_division=0)
            wa = w * aligned
            fa = float(np.sum(wa * (pred != 0)) / np.sum(wa)) if np.sum(wa) > 0 else 0.0
            out.append((f1, fa))
        return out[0][0] - out[1][0], out[0][1] - out[1][1]

    point = stats(np.ones(n_cases))
    rng = np.random.default_rng(seed)
    d_f1, d_fa = [], []
    for _ in range(draws):
        w = np.zeros(n_cases)
        for g in strata.values():
            np.add.at(w, rng.choice(g, size=len(g), replace=True), 1.0)
        f, fa = stats(w)
        d_f1.append(f)
        d_fa.append(fa)
    q = [(1 - level) / 2, (1 + level) / 2]
    return {"macro_f1_diff_point": float(point[0]), "macro_f1_diff": [float(x) for x in np.quantile(d_f1, q)],
            "false_alarm_diff_point": float(point[1]), "false_alarm_diff": [float(x) for x in np.quantile(d_fa, q)],
            "draws": draws, "level": level, "resampled": "held-out cases within each class, all conditions together"}


def quality_report(new_bundle: Any, old_bundle: Any, plant: PlantDescription, cases: list[dict],
                   disps: list, seed: int, *, progress: Callable[[int, int], None] | None = None,
                   old_label: str | None = None, old_outcomes: dict[str, list] | None = None) -> dict[str, Any]:
    """The plant's quality report: ``new_bundle`` and ``old_bundle`` (the active model) diagnosed on the same
    held-out recordings under every :func:`report_conditions` condition; per condition and pooled figures
    (:func:`_figures`), Wilson intervals of the rates, the paired bootstrap of the differences
    (:func:`paired_bootstrap`), and :func:`decide`'s decision. ``old_outcomes``: a dict that keeps
    ``old_bundle``'s outcomes per condition (filled when empty; reused when the same recordings are scored
    against several new models, as the learning curve does)."""
    from .robustness import run_condition

    t0 = time.perf_counter()
    conds = report_conditions()
    names = list(new_bundle.model.bands_.names)
    edges = np.asarray(new_bundle.model.bands_.edges, dtype=float)
    outs: dict[str, dict[str, list]] = {"new": {}, "active": {}}
    steps, done = 2 * len(conds), 0
    for who, bundle in (("new", new_bundle), ("active", old_bundle)):
        for cond in conds:
            if who == "active" and old_outcomes is not None and cond.name in old_outcomes:
                outs[who][cond.name] = old_outcomes[cond.name]
            else:
                outs[who][cond.name] = run_condition(bundle, cond, cases, disps, seed)
            if who == "active" and old_outcomes is not None:
                old_outcomes[cond.name] = outs[who][cond.name]
            done += 1
            if progress is not None:
                progress(done, steps)
    rows: dict[str, Any] = {}
    for cond in conds:
        rows[cond.name] = {who: _figures(outs[who][cond.name], names, edges) for who in outs}
    pooled = {}
    for who in outs:
        allo = [o for c in conds for o in outs[who][c.name]]
        f = _figures(allo, names, edges)
        f["false_alarm_interval"] = _wilson(f.get("false_alarms", 0), f.get("n_aligned", 0))
        f["confident_share_interval"] = _wilson(round(f.get("confident_share", 0.0) * f["n"]), f["n"])
        f["interval_coverage_interval"] = (None if f.get("interval_coverage") is None else
                                           _wilson(round(f["interval_coverage"] * f["n"]), f["n"]))
        pooled[who] = f
    mechs = [c["label_mechanism"] for c in cases]
    boot = paired_bootstrap(outs["new"], outs["active"], names, edges, mechs, seed=seed)
    report = {
        "plant": plant.name, "rated_speed_rpm": list(plant.rated_speed_rpm),
        "models": {"new": new_bundle.version, "active": old_label or old_bundle.version},
        "held_out": {"n_cases": len(cases), "n_failed": sum(d is None for d in disps), "seed_stream": [REPORT_STREAM, seed],
                     "per_class": {m: mechs.count(m) for m in sorted(set(mechs))},
                     "speed_rpm_range": [float(min(c["speed_rpm"] for c in cases)),
                                         float(max(c["speed_rpm"] for c in cases))],
                     "plant_model": "train" if plant.is_train else "lumped",
                     "tolerances": dict(TRAIN_TOLERANCES if plant.is_train else PLANT_TOLERANCES)},
        "conditions": [c.name for c in conds],
        "conditions_left_out": "the robustness report's rows on other simulated plants (rated-machine presets, far "
                               "plants) are not about this plant",
        "pooled": pooled, "per_condition": rows, "paired_bootstrap": boot,
        "wall_time_s": round(time.perf_counter() - t0, 1),
    }
    report["decision"] = decide(report)
    return report


def decide(report: Mapping[str, Any]) -> dict[str, Any]:
    """Whether the new model is better than the active one on this plant's report, and good enough on its own to
    be activated without being forced (docs/models.md):

    1. its pooled band macro-F1 is higher than the active model's (point estimate);
    2. its false alarms are not higher beyond the bootstrap interval: the 90 % paired bootstrap interval of
       (new − active) false-alarm rate reaches 0 or below;
    3. it gives no confident verdict two or more bands off, under any condition;
    4. it answered (was not refused on) at least as many recordings as the active model;
    5. the floors, whatever the active model scores: false-alarm rate at most :data:`FLOOR_FALSE_ALARM_RATE` and at
       most :data:`FLOOR_CONFIDENT_TWO_BANDS_OFF` confident verdicts two bands off under every condition, and at
       least :data:`FLOOR_DETECTION_RATE` of the moderate-or-worse machines given slight or worse, pooled. Why:
       "better than the active model" alone activated a model with 65.5 % false alarms because the shipped one
       had 91 %.

    Returns ``{"better": bool, "failed": [...], "held": [...], "floors": {...}, "rule": str}``: each point's line
    with its figures, in ``failed`` or ``held``.
    """
    p, boot = report["pooled"], report["paired_bootstrap"]
    new, old = p["new"], p["active"]
    floors = {"false_alarm_rate_max": FLOOR_FALSE_ALARM_RATE,
              "confident_two_bands_off_max": FLOOR_CONFIDENT_TWO_BANDS_OFF,
              "moderate_or_worse_detected_min": FLOOR_DETECTION_RATE}
    rule = ("macro-F1 higher AND false alarms not higher beyond the 90 % paired bootstrap interval AND no confident "
            "verdict two bands off AND no more recordings refused, AND the floors: false alarms "
            f"<= {FLOOR_FALSE_ALARM_RATE:.0%} and <= {FLOOR_CONFIDENT_TWO_BANDS_OFF} confident verdicts two bands off "
            f"under every condition, moderate-or-worse given slight or worse >= {FLOOR_DETECTION_RATE:.0%} "
            "(docs/models.md)")
    if not new.get("n"):
        none = "the new model answered none of the held-out recordings"
        return {"better": False, "failed": [none], "held": [], "reasons": [none], "floors": floors, "rule": rule}
    failed: list[str] = []
    held: list[str] = []
    f1_new, f1_old = new["macro_f1"], old.get("macro_f1", 0.0)
    (failed if not f1_new > f1_old else held).append(
        f"band macro-F1 {f1_new:.3f} vs the active model's {f1_old:.3f} (90 % bootstrap interval of the difference "
        f"{boot['macro_f1_diff'][0]:+.3f}…{boot['macro_f1_diff'][1]:+.3f}): {'higher' if f1_new > f1_old else 'not higher'}")
    lo_fa = boot["false_alarm_diff"][0]
    (failed if lo_fa > 0 else held).append(
        f"false alarms {new.get('false_alarm_rate') or 0:.1%} vs {old.get('false_alarm_rate') or 0:.1%} "
        f"(difference's interval {boot['false_alarm_diff'][0]:+.3f}…{boot['false_alarm_diff'][1]:+.3f}): "
        + ("higher beyond the bootstrap interval" if lo_fa > 0 else "not higher beyond the bootstrap interval"))
    off2 = new.get("confident_two_bands_off", 0)
    (failed if off2 else held).append(f"{off2} confident verdict(s) two or more bands off")
    if new.get("refused", 0) > old.get("refused", 0):
        failed.append(f"refused {new['refused']} recordings, the active model {old.get('refused', 0)}")
    for ok, line in _floor_lines(report):
        (held if ok else failed).append(line)
    return {"better": not failed, "failed": failed, "held": held, "floors": floors, "rule": rule}


def _floor_lines(report: Mapping[str, Any]) -> list[tuple[bool, str]]:
    """Whether the new model reaches each floor of :func:`decide` on ``report``, and its line with the figures (the
    conditions above a floor named, worst first). A report without per-condition rows is judged on its pooled
    figures as one condition. A floor the report cannot measure (no healthy, or no moderate-or-worse, machine among
    its recordings) is not reached."""
    rows = {name: r["new"] for name, r in (report.get("per_condition") or {}).items()}
    if not rows:
        rows = {"pooled": report["pooled"]["new"]}
    fa = {name: r.get("false_alarm_rate") for name, r in rows.items()}
    over = sorted(((v, n) for n, v in fa.items() if v is not None and v > FLOOR_FALSE_ALARM_RATE), reverse=True)
    measured = [v for v in fa.values() if v is not None]
    if over:
        fa_line = (f"floor: false alarms <= {FLOOR_FALSE_ALARM_RATE:.0%} under every condition: above it under "
                   f"{len(over)} of {len(rows)} (" + ", ".join(f"{n} {v:.1%}" for v, n in over[:5])
                   + (", …" if len(over) > 5 else "") + ")")
    elif measured:
        fa_line = (f"floor: false alarms <= {FLOOR_FALSE_ALARM_RATE:.0%} under every condition: held (worst "
                   f"{max(measured):.1%})")
    else:
        fa_line = "floor: false alarms: no healthy machine among the held-out recordings: not measured, not reached"
    off = sorted(((int(r.get("confident_two_bands_off") or 0), n) for n, r in rows.items()
                  if int(r.get("confident_two_bands_off") or 0) > FLOOR_CONFIDENT_TWO_BANDS_OFF), reverse=True)
    off_line = (f"floor: at most {FLOOR_CONFIDENT_TWO_BANDS_OFF} confident verdict(s) two or more bands off under "
                "every condition: " + (", ".join(f"{n} {k}" for k, n in off) if off else "held"))
    det = report["pooled"]["new"].get("moderate_or_worse_detected")
    n_det = report["pooled"]["new"].get("n_moderate_or_worse", 0)
    det_ok = det is not None and det >= FLOOR_DETECTION_RATE
    det_line = (f"floor: moderate-or-worse machines given slight or worse >= {FLOOR_DETECTION_RATE:.0%}: "
                + ("no moderate-or-worse machine among the held-out recordings: not measured, not reached"
                   if det is None else
                   f"{det:.1%} of {n_det} ({'held' if det_ok else 'below'})"))
    return [(not over and bool(measured), fa_line), (not off, off_line), (det_ok, det_line)]


def format_report(report: Mapping[str, Any]) -> str:
    """The report as a plain-text table (``rotordiag retrain``, ``rotordiag models show``)."""
    p = report["pooled"]
    m = report["models"]
    lines = [f"quality report for {report['plant']} ({report['held_out']['n_cases']} held-out recordings × "
             f"{len(report['conditions'])} measurement conditions): {m['new']} vs the active {m['active']}",
             f"{'condition':<46s} {'F1 new':>7s} {'F1 act':>7s} {'FA new':>7s} {'FA act':>7s} "
             f"{'conf new':>8s} {'conf act':>8s} {'off2 n/a':>8s} {'cov new':>7s} {'cov act':>7s}"]

    def pct(v: Any) -> str:
        return "–" if v is None else f"{v:.0%}"

    def row(name: str, r: Mapping[str, Any]) -> str:
        a, b = r["new"], r["active"]
        return (f"{name[:46]:<46s} {a.get('macro_f1', float('nan')):7.2f} {b.get('macro_f1', float('nan')):7.2f} "
                f"{pct(a.get('false_alarm_rate')):>7s} {pct(b.get('false_alarm_rate')):>7s} "
                f"{pct(a.get('confident_share')):>8s} {pct(b.get('confident_share')):>8s} "
                f"{a.get('confident_two_bands_off', 0):>4d}/{b.get('confident_two_bands_off', 0):<3d} "
                f"{pct(a.get('interval_coverage')):>7s} {pct(b.get('interval_coverage')):>7s}")

    for name, r in report["per_condition"].items():
        lines.append(row(name, r))
    lines.append(row("ALL (pooled)", p))
    for who in ("new", "active"):
        f = p[who]
        if not f.get("direction_estimated"):
            lines.append(f"direction ({who}): not estimated — the model has no direction heads")
            continue
        lines.append(f"direction ({who}, within ±{DIRECTION_TOLERANCE_DEG:.0f}° of the true one, DC available, "
                     f"misaligned): {_share(f.get('direction_accuracy'), f.get('direction_accuracy_interval'))} of "
                     f"{f.get('direction_n')}; confident with Δ ≥ {DIRECTION_MIN_DELTA}: "
                     f"{_share(f.get('direction_accuracy_confident'), f.get('direction_accuracy_confident_interval'))} "
                     f"of {f.get('direction_confident_n')}; true direction inside the answer's 90 % arc: "
                     f"{_share(f.get('direction_interval_coverage'), None)}; angular offset: "
                     + ("not estimated" if not f.get("angular_n") else
                        f"coverage {f['angular_coverage']:.0%} of {f['angular_n']}, MAE {f['angular_mae_mrad']:.4f} mrad, "
                        f"Spearman {f['angular_spearman'] if f['angular_spearman'] is not None else float('nan'):.2f}"))
    if "ood_share" in p["new"]:
        lines.append(f"flagged out of distribution (pooled): new {p['new']['ood_share']:.0%}, "
                     f"active {p['active'].get('ood_share', float('nan')):.0%}")
    b = report["paired_bootstrap"]
    lines.append(f"new − active, 90 % paired bootstrap: macro-F1 {b['macro_f1_diff_point']:+.3f} "
                 f"({b['macro_f1_diff'][0]:+.3f}…{b['macro_f1_diff'][1]:+.3f}), false-alarm rate "
                 f"{b['false_alarm_diff_point']:+.3f} ({b['false_alarm_diff'][0]:+.3f}…{b['false_alarm_diff'][1]:+.3f})")
    d = report["decision"]
    lines.append(("BETTER on this plant: " if d["better"] else "NOT better on this plant: ")
                 + "; ".join(d.get("failed") or d.get("held") or d.get("reasons", [])))
    return "\n".join(lines)


def _share(v: float | None, iv: list[float] | None) -> str:
    if v is None:
        return "–"
    return f"{v:.0%}" + ("" if iv is None else f" ({iv[0]:.0%}…{iv[1]:.0%})")


REPORT_FILE = "plant_report.json"


def store_report(registry: Any, version: str, report: Mapping[str, Any]) -> None:
    """Write ``report`` next to ``version``'s model and its summary (decision, pooled figures) into its card."""
    from .registry import dumps_json

    registry.write_file(version, REPORT_FILE, dumps_json(report))
    summary = {"pending": False, "plant": report["plant"], "compared_with": report["models"]["active"],
               "better": report["decision"]["better"], "decision": report["decision"],
               "pooled": report["pooled"], "paired_bootstrap": report["paired_bootstrap"], "file": REPORT_FILE}
    registry.update_card(version, {"plant_report": summary})


def pending_card(plant: PlantDescription) -> dict[str, Any]:
    """Card fields of a plant-retrained version at registration: the plant, and a report still pending (so
    that nothing activates the version before its report says it is better)."""
    return {"plant": plant.to_dict(), "plant_report": {"pending": True, "plant": plant.name}, "activated_by": None}


def report_and_activate(registry: Any, version: str, plant: PlantDescription, compare_with: Any, *,
                        seed: int = 0, n_per_class: int = DEFAULT_REPORT_CASES, activate: bool = True,
                        force: bool = False, progress: Callable[[str, int, int], None] | None = None,
                        cache: Path | None = None, compare_label: str | None = None) -> tuple[dict[str, Any], str | None]:
    """Simulate the held-out recordings, write ``version``'s quality report against ``compare_with`` (a
    ``models.predict.ModelBundle``, the active model), and activate ``version`` when ``activate`` and the
    report says it is better, or when ``force``. Returns ``(report, activated_by)`` (None: not activated).

    ``cache``: a folder where the held-out simulations are kept (named by a hash of the cases).
    ``progress(stage, done, total)`` is called per simulated case (``"held-out simulation"``) and per
    condition and model (``"report"``).
    """
    import hashlib
    import json

    from .predict import load_bundle

    cases = held_out_cases(plant, n_per_class, seed)
    if cache is not None:                      # a folder: the file is named by the cases themselves
        cache = cache / f"held_out_{hashlib.sha256(json.dumps(cases, sort_keys=True).encode()).hexdigest()[:16]}.npz"
    disps = simulate_held_out(cases, cache=cache, progress=None if progress is None else
                              (lambda d, t: progress("held-out simulation", d, t)))
    new = load_bundle(registry.root, version)
    report = quality_report(new, compare_with, plant, cases, disps, seed, old_label=compare_label,
                            progress=None if progress is None else (lambda d, t: progress("report", d, t)))
    store_report(registry, version, report)
    by = None
    if activate and (report["decision"]["better"] or force):
        registry.activate(version, force=force)
        by = registry.card(version).get("activated_by")
    return report, by


#: Seconds per unit of each retraining stage measured on one core of the 2-core machine (gen600_4pole, 24
#: samples: simulating and features per sample, training per feature row, held-out simulation per case, report per
#: case × condition × model), which weight the stages' shares of the progress fraction so that its linear ETA is sane
STAGE_SECONDS: dict[str, float] = {"simulating": 0.4, "features": 0.4, "training": 0.35,
                                   "held-out simulation": 0.5, "report": 0.07}
#: :data:`STAGE_SECONDS` of a shaft-train plant: the two simulation stages scaled by the measured CPU cost of a
#: gen600_4pole train against a lumped case (training sample 0.55 s against 0.15 s: ×3.6; held-out case of 195
#: revolutions 2.0 s against 0.21 s: ×9.6; docs/models.md, "Learning curve"), the other stages as the lumped
#: plant's (the same features, recipe and report)
TRAIN_STAGE_SECONDS: dict[str, float] = {"simulating": 1.45, "features": 0.4, "training": 0.35,
                                         "held-out simulation": 4.8, "report": 0.07}


def stage_seconds(plant: PlantDescription) -> dict[str, float]:
    """The expected seconds per unit of each retraining stage for ``plant``'s model (train or lumped)."""
    return dict(TRAIN_STAGE_SECONDS if plant.is_train else STAGE_SECONDS)


def n_report_classes(plant: PlantDescription) -> int:
    """Classes of held-out cases of a report (:func:`held_out_cases`): the mechanisms (lumped) or the couplings
    (train), and the aligned."""
    from .robustness import MECHANISMS

    return (len(plant.couplings()) if plant.is_train else len(MECHANISMS)) + 1


def retrain_units(plant: PlantDescription, n_samples: int, n_per_class: int, augment_copies: int = 0) -> dict[str, int]:
    """The units of each retraining stage (:class:`StagedProgress`): samples simulated, feature rows, training
    rows, held-out cases, condition × model report steps × cases."""
    cases = n_report_classes(plant) * n_per_class
    return {"simulating": n_samples, "features": n_samples, "training": n_samples * (1 + augment_copies),
            "held-out simulation": cases, "report": 2 * len(report_conditions()) * cases}


class StagedProgress:
    """One fraction 0–1 over the retraining stages, each weighted by its expected seconds
    (``seconds`` — :func:`stage_seconds` of the plant, :data:`STAGE_SECONDS` by default — × its units), with the
    ETA of that fraction.

    ``units``: stage → how many units it has (:func:`retrain_units`). ``update(stage, done, total)`` returns
    ``(fraction, eta_s)``; ``eta_s`` is the elapsed time × (1 − fraction) / fraction (None before 1 %): the
    measured rate of the work done so far applied to the rest, the stages' weights only saying how the rest
    compares with what was done.
    """

    def __init__(self, units: Mapping[str, int], clock: Callable[[], float] = time.monotonic,
                 seconds: Mapping[str, float] | None = None) -> None:
        per = dict(STAGE_SECONDS if seconds is None else seconds)
        w = {s: per[s] * max(int(units.get(s, 0)), 0) for s in STAGE_SECONDS}
        total = sum(w.values()) or 1.0
        self.share = {s: v / total for s, v in w.items()}
        self.start: dict[str, float] = {}
        acc = 0.0
        for s in STAGE_SECONDS:
            self.start[s] = acc
            acc += self.share[s]
        self._clock = clock
        self._t0 = clock()

    def update(self, stage: str, done: int, total: int) -> tuple[float, float | None]:
        f = self.start[stage] + self.share[stage] * (min(done, total) / total if total else 1.0)
        f = min(max(f, 0.0), 1.0)
        elapsed = self._clock() - self._t0
        eta = elapsed * (1.0 - f) / f if f >= 0.01 else None
        return f, eta


#: A feature column measured (not NaN) on fewer plants than this is dropped from a plant's training table
MIN_MEASURED_PLANTS = 20


def drop_unmeasured(table: Any, min_plants: int = MIN_MEASURED_PLANTS) -> tuple[Any, list[str]]:
    """Drop feature columns measured on fewer than ``min_plants`` plants (NaN in every other row: e.g. motion type
    for records shorter than the classifier needs, the sub-synchronous peak order, which only some plants show).

    A column seen on a few plants carries little to learn from, and a cross-validation fold without any of them
    holds it all NaN, which scikit-learn's histogram gradient boosting fails to bin (a retrain of 32 samples of
    gen600_4pole did: 5 of its 32 plants had a sub-synchronous line). The verdict maps features by name, so the
    model simply does not use them.
    """
    measured = ~np.isnan(table.X)
    pid = np.asarray(table.plant_id)
    never = [n for j, n in enumerate(table.feature_names)
             if len(np.unique(pid[measured[:, j]])) < min(min_plants, len(np.unique(pid)))
             or not measured[:, j].any()]
    return (table.without_features(never) if never else table), never
