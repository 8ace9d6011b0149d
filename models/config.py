"""Training configuration (``train.toml``), validated with messages that name the key.

Every section and key is optional; the defaults are the documented ones::

    seed = 0

    [bands]
    edges = [0.05, 0.15, 0.35]
    names = ["aligned", "slight", "moderate", "severe"]

    [features]
    # glob patterns of feature names the model must not use; default: absolute 1X–3X
    # phases, which without a keyphasor are relative to the first sample (arbitrary)
    exclude = ["b?_[xy]_[123]x_phase_deg"]
    clearance_features = ["*_per_c", "*_per_c2"]   # features that need the clearance
    clearance_dropout = 0.5     # share of training rows whose clearance features are
                                # blanked, so the model also works without the clearance
    clearance_heads = false     # a classifier and a Δ regressor for each case (with and
                                # without the clearance); the dropout then shapes only the
                                # OOD scorer, the envelope and the training medians
    monotonic_increasing = []   # patterns along which severity and Δ must not decrease
                                # (needs kind = "ordinal")

    [classifier]                # kind = "multiclass" (SeverityClassifier, default) or
    calibration = "temperature" # "ordinal" (OrdinalSeverityClassifier); then its parameters
    [regressor]                 # ConformalIntervalRegressor parameters
    alpha = 0.1
    [ood]                       # KNNDistanceOOD parameters
    threshold_quantile = 0.99
    [envelope]                  # FeatureEnvelope parameters (used when [features]
    quantile = 0.99             # envelope_features names features)

    [evaluation]
    n_splits = 5                # GroupKFold over plant_id
    speed_bands_rpm = [1200, 1800, 2400, 3000]

    [baselines]
    ratio_features = ["b?_[xy]_2x_1x_ratio"]   # 2X/1X of each bearing's x and y
    rule_cuts = [0.5, 1.0, 2.0]

    [augment]                   # measurement realities added to the table (models/augment.py)
    copies = 0                  # augmented rows per sample
    gain_mismatch = 0.0         # ±relative probe gain error
    bearing_sets = []           # [{bearings = [2, 3], weight = 1}, ...]
    speed_unknown = 0.0         # share of copies extracted without the speed
    seed = 0

    [direction]                 # models/direction.py
    heads = false               # fit the offset-direction (and angular-offset) heads when the
                                # dataset records each sample's offset_angle_rad
"""
from __future__ import annotations

import inspect
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rotordiag.core.bands import SeverityBands
from rotordiag.core.tables import deep_merge

from .augment import Augmentation
from .baselines import DEFAULT_RATIO_PATTERNS, DEFAULT_RULE_CUTS
from .estimators import ConformalIntervalRegressor, FeatureEnvelope, KNNDistanceOOD, SeverityClassifier
from .ordinal import OrdinalSeverityClassifier

_CLASSIFIERS = {"multiclass": SeverityClassifier, "ordinal": OrdinalSeverityClassifier}

DEFAULT_EXCLUDE: tuple[str, ...] = ("b?_[xy]_[123]x_phase_deg",)
DEFAULT_CLEARANCE_FEATURES: tuple[str, ...] = ("*_per_c", "*_per_c2")
_FEATURE_KEYS = {"exclude", "clearance_features", "clearance_dropout", "clearance_heads", "monotonic_increasing", "ood_features",
                 "ood_log_scales", "envelope_features", "envelope_upper_only"}
_SECTIONS = {"seed", "bands", "features", "classifier", "regressor", "ood", "envelope", "evaluation", "baselines",
             "augment", "direction"}


def _params(cls, section: str, d: Mapping[str, Any] | None) -> dict:
    d = dict(d or {})
    allowed = set(inspect.signature(cls.__init__).parameters) - {"self"}
    unknown = set(d) - allowed
    if unknown:
        raise ValueError(f"[{section}]: unknown key(s) {sorted(unknown)}; allowed: {sorted(allowed)}")
    return d


@dataclass(frozen=True)
class TrainConfig:
    """Validated training configuration (see the module docstring for the TOML form)."""

    seed: int = 0
    bands: SeverityBands = field(default_factory=SeverityBands)
    exclude_features: tuple[str, ...] = DEFAULT_EXCLUDE
    clearance_features: tuple[str, ...] = DEFAULT_CLEARANCE_FEATURES
    clearance_dropout: float = 0.5
    clearance_heads: bool = False
    monotonic_increasing: tuple[str, ...] = ()
    ood_features: tuple[str, ...] = ()
    ood_log_scales: dict[str, float] = field(default_factory=dict)
    classifier_kind: str = "multiclass"
    classifier: dict = field(default_factory=dict)
    regressor: dict = field(default_factory=dict)
    ood: dict = field(default_factory=dict)
    envelope_features: tuple[str, ...] = ()
    envelope_upper_only: tuple[str, ...] = ()
    envelope: dict = field(default_factory=dict)
    n_splits: int = 5
    speed_bands_rpm: tuple[float, ...] = (1200.0, 1800.0, 2400.0, 3000.0)
    ratio_features: tuple[str, ...] = DEFAULT_RATIO_PATTERNS
    rule_cuts: tuple[float, ...] = DEFAULT_RULE_CUTS
    augment: Augmentation = field(default_factory=Augmentation)
    direction_heads: bool = False

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> TrainConfig:
        d = dict(d or {})
        unknown = set(d) - _SECTIONS
        if unknown:
            raise ValueError(f"train config: unknown section(s) {sorted(unknown)}; allowed: {sorted(_SECTIONS)}")
        seed = d.get("seed", 0)
        if not isinstance(seed, int) or seed < 0:
            raise ValueError(f"seed: must be a non-negative integer, got {seed!r}")
        feats = dict(d.get("features", {}))
        if set(feats) - _FEATURE_KEYS:
            raise ValueError(
                f"[features]: unknown key(s) {sorted(set(feats) - _FEATURE_KEYS)}; allowed: {sorted(_FEATURE_KEYS)}"
            )
        dropout = feats.get("clearance_dropout", 0.5)
        if not isinstance(dropout, (int, float)) or not (0.0 <= float(dropout) <= 1.0):
            raise ValueError(f"[features] clearance_dropout: must lie in [0, 1], got {dropout!r}")
        heads = feats.get("clearance_heads", False)
        if not isinstance(heads, bool):
            raise ValueError(f"[features] clearance_heads: true or false, got {heads!r}")
        direction = dict(d.get("direction", {}))
        if set(direction) - {"heads"}:
            raise ValueError(f"[direction]: unknown key(s) {sorted(set(direction) - {'heads'})}; allowed: ['heads']")
        if not isinstance(direction.get("heads", False), bool):
            raise ValueError(f"[direction] heads: true or false, got {direction['heads']!r}")
        ev = dict(d.get("evaluation", {}))
        if set(ev) - {"n_splits", "speed_bands_rpm"}:
            raise ValueError(
                f"[evaluation]: unknown key(s) {sorted(set(ev) - {'n_splits', 'speed_bands_rpm'})}; "
                "allowed: ['n_splits', 'speed_bands_rpm']"
            )
        n_splits = ev.get("n_splits", 5)
        if not isinstance(n_splits, int) or n_splits < 2:
            raise ValueError(f"[evaluation] n_splits: must be an integer ≥ 2, got {n_splits!r}")
        sb = tuple(float(v) for v in ev.get("speed_bands_rpm", (1200.0, 1800.0, 2400.0, 3000.0)))
        if len(sb) < 2 or any(b <= a for a, b in zip(sb, sb[1:])):
            raise ValueError(f"[evaluation] speed_bands_rpm: need ≥ 2 increasing edges, got {list(sb)}")
        bl = dict(d.get("baselines", {}))
        if set(bl) - {"ratio_features", "rule_cuts"}:
            raise ValueError(
                f"[baselines]: unknown key(s) {sorted(set(bl) - {'ratio_features', 'rule_cuts'})}; "
                "allowed: ['ratio_features', 'rule_cuts']"
            )
        bands = SeverityBands.from_dict(d.get("bands"))
        rule_cuts = tuple(float(c) for c in bl.get("rule_cuts", DEFAULT_RULE_CUTS))
        if len(rule_cuts) != bands.n_bands - 1:
            raise ValueError(
                f"[baselines] rule_cuts: need one cut per band edge ({bands.n_bands - 1}), got {list(rule_cuts)}"
            )
        clf = dict(d.get("classifier", {}))
        kind = clf.pop("kind", "multiclass")
        if kind not in _CLASSIFIERS:
            raise ValueError(f"[classifier] kind: one of {sorted(_CLASSIFIERS)}, got {kind!r}")
        mono = feats.get("monotonic_increasing", ())
        if not isinstance(mono, (list, tuple)) or not all(isinstance(p, str) for p in mono):
            raise ValueError(f"[features] monotonic_increasing: a list of feature-name patterns, got {mono!r}")
        if mono and kind != "ordinal":
            raise ValueError("[features] monotonic_increasing: needs [classifier] kind = \"ordinal\" (a multiclass "
                             "classifier cannot take monotonic constraints)")
        ood_feats = feats.get("ood_features", ())
        if not isinstance(ood_feats, (list, tuple)) or not all(isinstance(p, str) for p in ood_feats):
            raise ValueError(f"[features] ood_features: a list of feature-name patterns, got {ood_feats!r}")
        ood_log = feats.get("ood_log_scales", {})
        if not isinstance(ood_log, Mapping) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 for v in ood_log.values()):
            raise ValueError(f"[features] ood_log_scales: a table of pattern = positive scale, got {ood_log!r}")
        env_pats = {}
        for key in ("envelope_features", "envelope_upper_only"):
            v = feats.get(key, ())
            if not isinstance(v, (list, tuple)) or not all(isinstance(p, str) for p in v):
                raise ValueError(f"[features] {key}: a list of feature-name patterns, got {v!r}")
            env_pats[key] = tuple(v)
        cfg = cls(
            seed=seed,
            bands=bands,
            exclude_features=tuple(str(p) for p in feats.get("exclude", DEFAULT_EXCLUDE)),
            clearance_features=tuple(str(p) for p in feats.get("clearance_features", DEFAULT_CLEARANCE_FEATURES)),
            clearance_dropout=float(dropout),
            clearance_heads=heads,
            monotonic_increasing=tuple(mono),
            ood_features=tuple(ood_feats),
            ood_log_scales={str(k): float(v) for k, v in ood_log.items()},
            classifier_kind=kind,
            classifier=_params(_CLASSIFIERS[kind], "classifier", clf),
            regressor=_params(ConformalIntervalRegressor, "regressor", d.get("regressor")),
            ood=_params(KNNDistanceOOD, "ood", d.get("ood")),
            envelope_features=env_pats["envelope_features"],
            envelope_upper_only=env_pats["envelope_upper_only"],
            envelope=_params(FeatureEnvelope, "envelope", d.get("envelope")),
            n_splits=n_splits,
            speed_bands_rpm=sb,
            ratio_features=tuple(str(p) for p in bl.get("ratio_features", DEFAULT_RATIO_PATTERNS)),
            rule_cuts=rule_cuts,
            augment=Augmentation.from_dict(d.get("augment")),
            direction_heads=bool(direction.get("heads", False)),
        )
        # Validate the parameter values now, with messages naming the section.
        m = cfg.make_model(("x",))
        for section, est in (("classifier", m.classifier), ("regressor", m.regressor), ("ood", m.ood),
                             ("envelope", m.envelope)):
            try:
                est._validate_params()
            except ValueError as exc:  # sklearn's InvalidParameterError is a ValueError
                raise ValueError(f"[{section}]: {exc}") from None
        return cfg

    @classmethod
    def shipped(cls, overrides: Mapping[str, Any] | None = None) -> TrainConfig:
        """The shipped model's recipe (``models/default/train.toml``), with ``overrides`` laid over it.

        ``overrides`` holds train.toml tables or keys (``{"classifier": {"max_iter": 30}}``); each
        replaces only what it names (:func:`rotordiag.core.tables.deep_merge`; a list, such as
        ``[features] monotonic_increasing`` or ``[augment] bearing_sets``, is replaced whole). So a
        plant's retraining keeps the shipped model's physics priors, OOD and envelope features and
        measurement augmentation unless it says otherwise. Errors name the key, as :meth:`from_dict`.
        """
        return cls.from_dict(deep_merge(shipped_train_dict(), dict(overrides or {})))

    @classmethod
    def from_file(cls, path: str | Path) -> TrainConfig:
        p = Path(path)
        try:
            with p.open("rb") as fh:
                data = tomllib.load(fh)
        except FileNotFoundError:
            raise ValueError(f"config: file {p} does not exist") from None
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"config: {p} is not valid TOML ({exc})") from None
        return cls.from_dict(data)

    def to_dict(self) -> dict:
        """JSON/TOML-able form (recorded in the model card). ``[direction]`` only when the heads are on: a card
        written before direction heads existed reads as heads off, and a recipe without them serialises as it did."""
        out = {
            "seed": self.seed,
            "bands": self.bands.to_dict(),
            "features": {
                "exclude": list(self.exclude_features),
                "clearance_features": list(self.clearance_features),
                "clearance_dropout": self.clearance_dropout,
                "clearance_heads": self.clearance_heads,
                "monotonic_increasing": list(self.monotonic_increasing),
                "ood_features": list(self.ood_features),
                "ood_log_scales": dict(self.ood_log_scales),
                "envelope_features": list(self.envelope_features),
                "envelope_upper_only": list(self.envelope_upper_only),
            },
            "classifier": {"kind": self.classifier_kind, **dict(self.classifier)},
            "regressor": dict(self.regressor),
            "ood": dict(self.ood),
            "envelope": dict(self.envelope),
            "evaluation": {"n_splits": self.n_splits, "speed_bands_rpm": list(self.speed_bands_rpm)},
            "baselines": {"ratio_features": list(self.ratio_features), "rule_cuts": list(self.rule_cuts)},
            "augment": self.augment.to_dict(),
        }
        if self.direction_heads:
            out["direction"] = {"heads": True}
        return out

    def make_model(self, feature_names, *, clearance_seed: int | None = None):
        """An unfitted :class:`~models.estimators.MisalignmentModel` with this configuration.

        ``clearance_seed`` seeds the rows whose clearance features are blanked (default ``seed``).
        """
        from .estimators import MisalignmentModel

        seeded = {"random_state": self.seed}
        reg = {"lower_bound": 0.0, **seeded, **self.regressor}
        return MisalignmentModel(
            band_edges=self.bands.edges,
            band_names=self.bands.names,
            classifier=_CLASSIFIERS[self.classifier_kind](**{**seeded, **self.classifier}),
            regressor=ConformalIntervalRegressor(**reg),
            ood=KNNDistanceOOD(**{**seeded, **self.ood}),
            feature_names=tuple(feature_names),
            monotonic_increasing=self.monotonic_increasing,
            ood_features=self.ood_features,
            ood_log_scales=dict(self.ood_log_scales),
            envelope_features=self.envelope_features,
            envelope_upper_only=self.envelope_upper_only,
            envelope=FeatureEnvelope(**{**seeded, **self.envelope}),
            clearance_features=self.clearance_features,
            clearance_dropout=self.clearance_dropout,
            clearance_heads=self.clearance_heads,
            random_state=self.seed if clearance_seed is None else clearance_seed,
        )


def shipped_train_dict() -> dict[str, Any]:
    """The tables of the shipped model's ``train.toml`` (package data of ``rotordiag.models.default``)."""
    from importlib.resources import files

    return tomllib.loads(files("rotordiag.models.default").joinpath("train.toml").read_text(encoding="utf-8"))
