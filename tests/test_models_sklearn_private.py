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
