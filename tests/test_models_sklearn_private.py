"""scikit-learn's private internals that rotordiag relies on are still what it expects.

A scikit-learn release that changes one of them makes this test fail with a message
naming the internal (rather than the compiled predictor giving wrong verdicts).
"""
from __future__ import annotations

import ast
from pathlib import Path

from rotordiag.models._sklearn_private import check_internals

ROOT = Path(__file__).resolve().parents[1]
PRIVATE_NAMES = ("_predictors", "_baseline_prediction", "_TemperatureScaling", "_param_validation",
                 "_CalibratedClassifier", "_SigmoidCalibration", "_hist_gradient_boosting")


def test_internals_are_as_expected():
    check_internals()


def test_private_internals_are_used_in_one_module_only():
    users = {}
    for d in ("simulator", "features", "models", "service", "rotordiag"):
        for path in (ROOT / d).rglob("*.py"):
            text = path.read_text(encoding="utf-8")
            tree = ast.parse(text)
            names = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
            names |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
            names |= {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)}
            hits = {p for p in PRIVATE_NAMES for n in names if p in n}
            if hits:
                users[str(path.relative_to(ROOT))] = sorted(hits)
    assert list(users) == ["models/_sklearn_private.py"], users


def test_a_model_written_under_sklearn_1_8_loads(tmp_path):
    """scikit-learn 1.8 names HistGradientBoosting's compiled losses ``_loss.Cy*`` in a skops file
    (1.9 cannot import ``_loss``); such a file loads and predicts exactly as the model it holds."""
    import json
    import zipfile

    import numpy as np
    import skops.io as sio

    from rotordiag.models._sklearn_private import SKLEARN_RENAMED_TYPES
    from rotordiag.models.registry import TRUSTED_TYPES, load_model_bytes, load_model_file, shipped_registry_dir

    reg = shipped_registry_dir()
    model = load_model_file(reg / (reg / "active").read_text().strip() / "model.skops")
    new_to_old = {v: k for k, v in SKLEARN_RENAMED_TYPES.items()}
    renamed = 0

    def as_sklearn_18(node):
        nonlocal renamed
        if isinstance(node, dict):
            name = f"{node.get('__module__')}.{node.get('__class__')}"
            old = new_to_old.get(name, name if name in SKLEARN_RENAMED_TYPES else None)
            if old is not None:         # under scikit-learn 1.8 the dump already holds the old name
                node["__module__"], node["__class__"] = old.rsplit(".", 1)
                renamed += 1
            for v in node.values():
                as_sklearn_18(v)
        elif isinstance(node, list):
            for v in node:
                as_sklearn_18(v)

    src = tmp_path / "current.skops"
    src.write_bytes(sio.dumps(model))
    out = tmp_path / "as_1_8.skops"
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(out, "w") as zout:
        for info in zin.infolist():
            payload = zin.read(info.filename)
            if info.filename == "schema.json":
                schema = json.loads(payload)
                as_sklearn_18(schema)
                payload = json.dumps(schema).encode()
            zout.writestr(info, payload)
    assert renamed >= 2, "the shipped model should hold HistGradientBoosting losses (classifier and regressor)"
    assert set(SKLEARN_RENAMED_TYPES.values()) <= set(TRUSTED_TYPES)
    loaded = load_model_bytes(out.read_bytes(), "as_1_8.skops")
    probe = np.random.default_rng(0).normal(size=(32, model.feature_median_.size))
    np.testing.assert_array_equal(loaded.predict_proba(probe), model.predict_proba(probe))
