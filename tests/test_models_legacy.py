"""Model registries written before the rotordiag.* rename keep working (issue 11 item 3).

``tests/reference/legacy_registry`` was written by the code of commit bcdd415 (type names
``models.estimators.*``, ``models.bands.*``) together with the predictions it gave then
(``legacy_registry_expected.npz``); the shipped default registry was written before the
rename too.
"""
from __future__ import annotations

import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest
from threadpoolctl import threadpool_limits
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.models.legacy import LEGACY_TYPE_NAMES, renamed_skops_bytes
from rotordiag.models.registry import TRUSTED_TYPES, Registry, RegistryError, load_model_bytes, shipped_registry_dir

REFERENCE = Path(__file__).parent / "reference"


@pytest.fixture(autouse=True)
def _one_thread():
    with threadpool_limits(1):
        yield


def _schema(path: Path) -> str:
    with zipfile.ZipFile(path) as z:
        return z.read("schema.json").decode()


def test_fixture_really_holds_the_old_names():
    text = _schema(REFERENCE / "legacy_registry" / "v0001" / "model.skops")
    assert '"__module__": "models.estimators"' in text and "rotordiag" not in text


def test_legacy_registry_loads_and_predicts_as_when_it_was_written(tmp_path):
    reg = tmp_path / "reg"
    shutil.copytree(REFERENCE / "legacy_registry", reg)
    expected = np.load(REFERENCE / "legacy_registry_expected.npz")
    model, card = Registry(reg).load()
    np.testing.assert_allclose(model.predict_proba(expected["X"]), expected["proba"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(model.predict_misalignment(expected["X"])[1], expected["delta"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(model.ood_ratio(expected["X"]), expected["ood"], rtol=1e-12, atol=1e-15)
    assert type(model).__module__ == "rotordiag.models.estimators"


def test_migrate_command_rewrites_then_loads_identically(tmp_path):
    reg = tmp_path / "reg"
    shutil.copytree(REFERENCE / "legacy_registry", reg)
    expected = np.load(REFERENCE / "legacy_registry_expected.npz")
    result = CliRunner().invoke(app, ["models", "migrate", "--registry", str(reg)])
    assert result.exit_code == 0, result.output
    assert "migrated: v0001" in result.output
    text = _schema(reg / "v0001" / "model.skops")
    assert '"models.estimators"' not in text and '"rotordiag.models.estimators"' in text
    assert (reg / "v0001" / "model.skops.pre-rename").is_file()
    model, _ = Registry(reg).load()
    np.testing.assert_allclose(model.predict_proba(expected["X"]), expected["proba"], rtol=1e-12, atol=1e-15)
    again = CliRunner().invoke(app, ["models", "migrate", "--registry", str(reg)])
    assert again.exit_code == 0 and "nothing to migrate" in again.output


def test_shipped_registry_is_current_and_loads_without_renaming(tmp_path):
    # the shipped model was migrated with `rotordiag models migrate` (its pre-rename file
    # loaded 5.6 s slower through the in-memory mapping); old files are covered by
    # tests/reference/legacy_registry above
    src = shipped_registry_dir()
    version = (src / "active").read_text().strip()
    data = (src / version / "model.skops").read_bytes()
    assert renamed_skops_bytes(data) == (data, 0)
    assert not list(src.glob("*/model.skops.pre-rename"))
    reg = tmp_path / "shipped"
    shutil.copytree(src, reg)
    result = CliRunner().invoke(app, ["models", "migrate", "--registry", str(reg)], catch_exceptions=False)
    assert "nothing to migrate" in result.output
    model, _ = Registry(reg).load()
    X = np.random.default_rng(1).normal(size=(16, model.feature_median_.size))
    assert np.isfinite(model.predict_proba(X)).all()


def test_mapping_does_not_widen_the_trusted_list():
    # only this package's own classes are mapped, and each target is already trusted
    assert set(LEGACY_TYPE_NAMES.values()) <= set(TRUSTED_TYPES)
    assert all(k.startswith("models.") for k in LEGACY_TYPE_NAMES)
    assert not any(t.startswith("models.") for t in TRUSTED_TYPES)


def test_an_old_file_with_a_foreign_type_is_still_refused(tmp_path):
    src = REFERENCE / "legacy_registry" / "v0001" / "model.skops"
    # a type named like ours but not in the table, e.g. a look-alike module
    evil = tmp_path / "evil.skops"
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(evil, "w") as zout:
        for info in zin.infolist():
            payload = zin.read(info.filename)
            if info.filename == "schema.json":
                payload = payload.replace(b'"__module__": "models.estimators"', b'"__module__": "models.evil"', 1)
            zout.writestr(info, payload)
    new, _ = renamed_skops_bytes(evil.read_bytes())
    with pytest.raises(RegistryError, match="outside the trusted list"):
        load_model_bytes(new, "evil.skops")


def test_not_a_zip_is_a_clean_error():
    with pytest.raises(RegistryError, match="not a readable skops file"):
        load_model_bytes(b"not a zip", "x.skops")
