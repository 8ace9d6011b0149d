"""The dependency floors in pyproject.toml are true, and stay so.

``make test-lowest`` installs every declared dependency at its floor and runs the quick tests;
this module catches the obvious ways the floors go stale between such runs:

* a floor lowered below a version this project is known to need (the table below says why);
* an environment whose installed versions are below the floors (and, under ``make test-lowest``,
  i.e. with ``ROTORDIAG_EXPECT_FLOORS=1``, one whose versions are not exactly the floors);
* a third-party package imported by the code but not declared (so it has no floor at all).
"""
from __future__ import annotations

import ast
import importlib.util
import os
import sys
from importlib import metadata
from pathlib import Path
from types import ModuleType

import pytest
from packaging.utils import canonicalize_name
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = ROOT / "pyproject.toml"
CODE_DIRS = ("rotordiag", "simulator", "features", "models", "service")

#: the lowest version of each dependency this project is known to need, and why (checked by
#: installing it: ``make test-lowest``). A floor in pyproject.toml must not be below these.
KNOWN_MINIMUMS: dict[str, tuple[str, str]] = {
    "scikit-learn": ("1.8", "CalibratedClassifierCV(method='temperature') and _TemperatureScaling are new in 1.8 "
                            "(models/train.py, _sklearn_private.py); validate_data needs >= 1.6"),
    "scipy": ("1.15", "scipy.stats.qmc.Sobol(rng=...) (simulator/dataset/design.py) is new in 1.15"),
    "skops": ("0.14", "skops < 0.11 fails to import with scikit-learn >= 1.8 (sklearn.linear_model._sgd_fast.Huber "
                      "is gone); 0.11-0.13 do not trust HistGradientBoosting's loss, link and _BinMapper types, so "
                      "the model registry's trusted-types list would need 8 more private scikit-learn classes"),
    "threadpoolctl": ("3.2", "scikit-learn 1.8 requires threadpoolctl >= 3.2"),
    "numpy": ("1.26", "numba 0.59 and scipy 1.15 build on it; tested at 1.26.0 by make test-lowest"),
    "schemathesis": ("4.29.1", "tests/test_service_fuzz.py imports response_schema_conformance from "
                               "schemathesis.checks (absent up to 4.29.0)"),
    "hypothesis": ("6.130.12", "schemathesis 4.29.1 requires it"),
    "pytest": ("8.4", "schemathesis 4.29.1 requires it"),
    "typer": ("0.16", "typer < 0.16 fails with click >= 8.2 ('Secondary flag is not valid for non-boolean flag')"),
    "python-multipart": ("0.0.20", "up to 0.0.19 a multipart body holding only the closing boundary raises "
                                   "MultipartParseError under starlette 0.36: a 500 on POST /diagnose "
                                   "(found by tests/test_service_fuzz.py)"),
    "pydantic": ("2.6", "under 2.5 a job result holding NaN is not turned into null: GET /jobs/{id} fails with "
                        "'Out of range float values are not JSON compliant' (tests/test_service_infra.py)"),
    "anyio": ("4.5", "schemathesis 4.29.1 requires it, so no lower version can be tested"),
    "fastapi": ("0.133", "fastapi-standalone-docs 0.3.0 (the offline /docs and /redoc files) requires it"),
    "starlette": ("0.40", "fastapi 0.133 requires it"),
    "pyuff": ("2.5.8", "the UFF reader is tested with it (features/reader.py)"),
}

#: import names whose distribution name differs and that packages_distributions() may not map
#: (editable installs, namespace packages)
_IMPORT_TO_DIST = {"sklearn": "scikit-learn", "yaml": "pyyaml", "fastapi_standalone_docs": "fastapi-standalone-docs",
                   "tomli_w": "tomli-w", "multipart": "python-multipart", "python_multipart": "python-multipart"}


def _load_constraints_script() -> ModuleType:
    path = ROOT / ".ci" / "lowest_constraints.py"
    spec = importlib.util.spec_from_file_location("lowest_constraints", path)
    assert spec is not None and spec.loader is not None, f"cannot load {path}"
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


FLOORS: dict[str, str] = _load_constraints_script().floors(PYPROJECT)


@pytest.mark.parametrize("name", sorted(KNOWN_MINIMUMS))
def test_floor_is_not_below_a_known_minimum(name: str) -> None:
    minimum, why = KNOWN_MINIMUMS[name]
    assert name in FLOORS, f"{name} is not declared in pyproject.toml, but the project needs >= {minimum}: {why}"
    assert Version(FLOORS[name]) >= Version(minimum), (
        f"pyproject.toml declares {name}>={FLOORS[name]}, but {minimum} is the lowest that works: {why}")


@pytest.mark.parametrize("name", sorted(FLOORS))
def test_installed_version_satisfies_floor(name: str) -> None:
    try:
        installed = Version(metadata.version(name))
    except metadata.PackageNotFoundError:
        pytest.fail(f"{name} is declared in pyproject.toml but not installed; reinstall: pip install -e '.[dev]'")
    floor = Version(FLOORS[name])
    assert installed >= floor, f"{name} {installed} is installed, below the declared floor {floor}"
    if os.environ.get("ROTORDIAG_EXPECT_FLOORS") == "1":
        # make test-lowest pins every declared dependency to its floor: prove it did
        assert installed == floor, (
            f"make test-lowest should have installed {name}=={floor}, found {installed}")


def _third_party_imports() -> dict[str, str]:
    """``{top-level import name: first file importing it}`` for the package code (not tests)."""
    stdlib = set(sys.stdlib_module_names)
    found: dict[str, str] = {}
    for folder in CODE_DIRS:
        for path in sorted((ROOT / folder).rglob("*.py")):
            tree = ast.parse(path.read_text(), filename=str(path))
            for node in ast.walk(tree):
                if isinstance(node, ast.Import):
                    names = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names = [node.module]
                else:
                    continue
                for name in names:
                    top = name.split(".")[0]
                    if top not in stdlib and top != "rotordiag" and top != "__future__":
                        found.setdefault(top, str(path.relative_to(ROOT)))
    return found


def test_every_imported_package_is_declared_with_a_floor() -> None:
    dists = metadata.packages_distributions()
    undeclared = []
    for top, where in sorted(_third_party_imports().items()):
        candidates = {canonicalize_name(d) for d in dists.get(top, [])}
        if top in _IMPORT_TO_DIST:
            candidates.add(_IMPORT_TO_DIST[top])
        candidates.add(canonicalize_name(top))     # typer 0.12 ships the module in typer-slim
        if not candidates & set(FLOORS):
            undeclared.append(f"{top} (imported in {where}; distribution {sorted(candidates)})")
    assert not undeclared, ("imported by the package but not declared in pyproject.toml [project] dependencies "
                            f"with a floor: {undeclared}")


def test_constraints_script_refuses_a_dependency_without_floor(tmp_path: Path) -> None:
    bad = tmp_path / "pyproject.toml"
    bad.write_text('[project]\nname = "x"\ndependencies = ["numpy>=1.26", "scipy"]\n')
    with pytest.raises(SystemExit, match="scipy"):
        _load_constraints_script().floors(bad)
