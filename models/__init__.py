"""Severity models for generator–exciter coupling misalignment (issue 5, docs/models.md).

Public API (import from the submodules; importing ``models`` itself stays light):

models.predict
    ``load_bundle(registry_root, version=None) -> ModelBundle``;
    ``diagnose(bundle, feature_result, clearance_um=None) -> Verdict`` — the one verdict
    function, used by ``rotordiag diagnose`` and the service; ``format_verdict``.
models.diagnosis
    ``diagnose_recording(bundle, recording) -> (Verdict, FeatureResult)``: features, verdict, a
    doubtful estimated speed judged by the model (``models.speed_choice.choose_speed``) and the doubts
    that read the recording again (``models.checks.common_mode``, ``models.checks.clearance_check``) — what every
    caller that starts from a recording uses.
models.checks.bearing_sets, models.checks.numbering, models.checks.acquisitions
    Which probe set a verdict reads; bearings numbered from the other end; the coupling's bearings
    recorded in separate takes.
models.registry
    ``Registry(root)``: ``register``, ``load``, ``list``, ``activate``, ``rollback``,
    ``active_version``, ``card``; ``TRUSTED_TYPES`` (skops), ``RegistryError``.
models.estimators
    ``SeverityClassifier``, ``ConformalIntervalRegressor``, ``KNNDistanceOOD``,
    ``MisalignmentModel`` (scikit-learn estimators).
models.bands
    ``SeverityBands`` (aligned < 0.05 ≤ slight < 0.15 ≤ moderate < 0.35 ≤ severe by default).
models.dataset
    ``load_feature_table(path)`` / ``load_feature_tables(paths)``: dataset HDF5 → ``FeatureTable``
    through ``features.extract_features``, cached next to the file.
models.config, models.train, models.evaluate, models.baselines, models.metrics
    ``TrainConfig`` (train.toml), ``train_and_register``, held-out-plant evaluation and
    report, the 2X/1X baselines, metrics.
models.diagnose_files
    ``rotordiag diagnose`` on files: options (sidecar + flags), one verdict per file through
    ``features.reader.read_recording``, the CSV/JSON table of verdicts.
"""
