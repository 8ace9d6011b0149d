"""Severity models for generator–exciter coupling misalignment (issue 5, docs/models.md).

Public API (import from the submodules; importing ``models`` itself stays light):

models.pipeline
    ``diagnose_recording(bundle, recording) -> (Verdict, FeatureResult)``: the one verdict function — features
    once per speed hypothesis, model scores, checks (``models.checks``), status, verdict — used by the service,
    ``rotordiag diagnose`` and the benchmarks; ``diagnose(bundle, feature_result)`` from given features.
models.predict
    ``load_bundle(registry_root, version=None) -> ModelBundle``; ``model_scores``, ``verdict_of``,
    ``Verdict``, ``format_verdict``.
models.checks
    The checks of a verdict, one signature (``CheckContext`` in, reasons out): the probe set, separate
    acquisitions, reverse 2X, numbering, common mode, diametral clearance; the speed choice.
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
