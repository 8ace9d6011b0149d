"""The service database under Alembic (issue 47): a database the service wrote before Alembic is
adopted with its rows, the schema versions go up and down with the data kept, the migrated schema
equals the models', several replicas may migrate at once, and `rotordiag db copy` moves a SQLite
store into PostgreSQL. Backend-neutral tests run on SQLite and on a real PostgreSQL server."""
from __future__ import annotations

import datetime as dt
import sqlite3
import threading
from pathlib import Path

import pytest
from sqlalchemy import func, inspect, select, text

from rotordiag.service.core.db import (
    AssetBaseline,
    AssetBaselineRecording,
    AssetDiagnosis,
    AssetSettings,
    Base,
    CopyError,
    Job,
    copy_store,
    current_revision,
    head_revision,
    init_db,
    make_engine,
    migrate,
)

DUMP = Path(__file__).parent / "reference" / "service_db_before_alembic.sql"


def _old_sqlite(path: Path, drop: tuple[str, ...] = ()) -> str:
    """A SQLite file as the service wrote it before Alembic (tests/reference dump), minus ``drop`` columns
    of asset_diagnoses (what a still older version lacked)."""
    con = sqlite3.connect(path)
    con.executescript(DUMP.read_text())
    for col in drop:
        con.execute(f'ALTER TABLE asset_diagnoses DROP COLUMN "{col}"')
    con.commit()
    con.close()
    return f"sqlite:///{path}"


def _check_reference_rows(sessions) -> None:
    """The rows of the reference dump, read back through the models (values written by the old code)."""
    with sessions() as s:
        jobs = {j.id[-1]: j for j in s.scalars(select(Job))}
        assert jobs["1"].status == "succeeded" and jobs["1"].result == {"n_samples": 16}
        assert jobs["2"].status == "interrupted" and jobs["2"].params == {"spec_toml": "y"}
        assert jobs["1"].created_at == dt.datetime(2026, 11, 1, 12, 0, tzinfo=dt.UTC)
        assert jobs["2"].lease_owner is None and jobs["2"].lease_expires_at is None
        rows = list(s.scalars(select(AssetDiagnosis).order_by(AssetDiagnosis.id)))
        assert [r.id for r in rows] == [1, 2, 3]
        assert [r.misalignment for r in rows] == pytest.approx([0.20, 0.21, 0.22])
        assert rows[2].change == {"compared": True, "changed": True} and rows[2].alarm is True
        assert rows[0].verdict["severity"] == "moderate" and rows[1].signature == {"x1_amp_um_pp": 41.0}
        base = s.get(AssetBaseline, "unit-7")
        assert base is not None and base.diagnosis_ids == [1, 2] and base.signature == {"x1_amp_um_pp": 40.0}
        settings = s.get(AssetSettings, "unit-7")
        assert settings is not None and settings.thresholds == {"x1_amp_rel": 0.3}
        # v0008 gave the baseline its recordings, each with its diagnosis's own signature
        members = list(s.scalars(select(AssetBaselineRecording).order_by(AssetBaselineRecording.diagnosis_id)))
        assert [(m.asset_id, m.diagnosis_id) for m in members] == [("unit-7", 1), ("unit-7", 2)]
        assert [m.signature for m in members] == [{"x1_amp_um_pp": 40.0}, {"x1_amp_um_pp": 41.0}]
        assert [m.speed_rpm for m in members] == [1800.0, 1800.0] and members[0].model_version == "v0001"


def test_pre_alembic_sqlite_database_is_adopted_with_its_rows(tmp_path):
    engine = make_engine(_old_sqlite(tmp_path / "old.sqlite3"))
    assert current_revision(engine) is None
    sessions = init_db(engine)
    assert current_revision(engine) == head_revision() == "v0010"
    _check_reference_rows(sessions)
    init_db(engine)   # a second start changes nothing
    _check_reference_rows(sessions)


def test_older_database_lacking_nullable_columns_gets_them(tmp_path):
    engine = make_engine(_old_sqlite(tmp_path / "older.sqlite3", drop=("alarm", "change", "signature")))
    init_db(engine)
    cols = {c["name"] for c in inspect(engine).get_columns("asset_diagnoses")}
    assert {"alarm", "change", "signature"} <= cols
    with engine.connect() as conn:
        assert conn.execute(text("SELECT COUNT(*) FROM asset_diagnoses WHERE alarm IS NULL")).scalar_one() == 3


def test_versions_up_and_down_keep_the_rows(database_url):
    engine = make_engine(database_url)
    migrate(engine, "v0001")
    assert current_revision(engine) == "v0001"
    assert "lease_owner" not in {c["name"] for c in inspect(engine).get_columns("jobs")}
    with engine.begin() as conn:   # a job written by version v0001's code
        conn.execute(text("INSERT INTO jobs (id, kind, status, params, progress, stage, message, attempts, "
                          "created_at, updated_at) VALUES ('j1', 'dataset', 'running', '{\"n\": 3}', 0.5, "
                          "'simulating', 'm', 1, '2026-11-01 12:00:00', '2026-11-01 12:00:00')"))
    migrate(engine, "v0002")
    assert current_revision(engine) == "v0002"
    sessions = init_db(engine)
    assert current_revision(engine) == "v0010"
    with sessions() as s:
        job = s.get(Job, "j1")
        assert job is not None and job.params == {"n": 3} and job.progress == 0.5 and job.lease_expires_at is None
    migrate(engine, "v0001")
    assert current_revision(engine) == "v0001"
    assert "lease_owner" not in {c["name"] for c in inspect(engine).get_columns("jobs")}
    with engine.connect() as conn:
        assert conn.execute(text("SELECT status FROM jobs WHERE id = 'j1'")).scalar_one() == "running"
    assert "probes" not in {c["name"] for c in inspect(engine).get_columns("asset_settings")}
    migrate(engine, "v0004")
    assert "probes" in {c["name"] for c in inspect(engine).get_columns("asset_settings")}
    assert "setpoints" not in {c["name"] for c in inspect(engine).get_columns("asset_settings")}
    with engine.begin() as conn:   # settings written by version v0004's code
        conn.execute(text("INSERT INTO asset_settings (asset_id, thresholds, updated_at, probes) VALUES "
                          "('u1', '{}', '2026-11-01 12:00:00', '{\"units\": \"mil\"}')"))
    migrate(engine, "v0005")
    assert current_revision(engine) == "v0005"
    assert {"alarm_events", "webhooks", "webhook_deliveries"} <= set(inspect(engine).get_table_names())
    with engine.begin() as conn:   # v0005's code sets the setpoints
        assert conn.execute(text("SELECT setpoints FROM asset_settings")).scalar_one() is None
        conn.execute(text("UPDATE asset_settings SET setpoints = '{\"x1_um_pp\": {\"alert\": 75.0}}'"))
    migrate(engine, "v0004")   # v0005 down: its tables and column go, the row stays
    assert not {"alarm_events", "webhooks", "webhook_deliveries"} & set(inspect(engine).get_table_names())
    assert "setpoints" not in {c["name"] for c in inspect(engine).get_columns("asset_settings")}
    with engine.connect() as conn:
        assert conn.execute(text("SELECT asset_id FROM asset_settings")).scalar_one() == "u1"
    migrate(engine)
    assert current_revision(engine) == "v0010"
    with sessions.begin() as s:
        row = s.get(AssetSettings, "u1")
        assert row is not None and row.probes == {"units": "mil"} and row.setpoints is None
        row.site, row.setpoints = "Riverside", {"x1_um_pp": {"alert": 75.0}}
        s.add(AssetDiagnosis(asset_id="u1", model_version="v0001", severity="none", verdict={}, key_features={},
                             recorded_at=dt.datetime(2025, 3, 2, 8, 0, tzinfo=dt.UTC), tags={"load_mw": 350.0},
                             note="aligned on 2025-03-01"))
    with sessions() as s:
        d = s.scalars(select(AssetDiagnosis).where(AssetDiagnosis.asset_id == "u1")).one()
        assert d.recorded_at == dt.datetime(2025, 3, 2, 8, 0, tzinfo=dt.UTC) and d.tags == {"load_mw": 350.0}
        assert s.get(AssetSettings, "u1").site == "Riverside"
    migrate(engine, "v0006")   # v0007 down: site, unit, train go, the rest stays
    assert not {"site", "unit", "train"} & {c["name"] for c in inspect(engine).get_columns("asset_settings")}
    migrate(engine, "v0005")   # v0006 down: the recording time, tags and note go, the rows stay
    assert not {"recorded_at", "tags", "note"} & {c["name"] for c in inspect(engine).get_columns("asset_diagnoses")}
    with engine.connect() as conn:
        assert conn.execute(text("SELECT COUNT(*) FROM asset_diagnoses WHERE asset_id = 'u1'")).scalar_one() == 1
        assert conn.execute(text("SELECT setpoints FROM asset_settings")).scalar_one() is not None
    migrate(engine)
    assert current_revision(engine) == "v0010"
    engine.dispose()


def test_v0008_baseline_recordings_up_and_down(database_url):
    """v0008 gives each baseline its recordings (a one-recording baseline its own signature; a baseline of several
    only when every recording still keeps its signature), goes down with the baselines kept, and up again."""
    engine = make_engine(database_url)
    migrate(engine, "v0007")
    with engine.begin() as conn:   # rows written by version v0007's code
        for i, (asset, sig) in enumerate([("a1", '{"speed_rpm": 3000.0}'), ("a2", '{"speed_rpm": 3001.0}'),
                                          ("a2", '{"speed_rpm": 3002.0}'), ("a3", None), ("a3", '{"s": 1}')], 1):
            conn.execute(text("INSERT INTO asset_diagnoses (id, asset_id, created_at, model_version, severity, "
                              "speed_rpm, verdict, key_features, signature) VALUES (:i, :a, '2026-11-02 10:00:00', "
                              "'v0002', 'aligned', 3000.0, '{}', '{}', :sig)"), {"i": i, "a": asset, "sig": sig})
        for asset, ids, sig in (("a1", "[1]", '{"avg": 1}'), ("a2", "[2, 3]", '{"avg": 2}'),
                                ("a3", "[4, 5]", '{"avg": 3}'), ("a4", "[99]", '{"avg": 4}')):
            conn.execute(text("INSERT INTO asset_baselines (asset_id, created_at, source, diagnosis_ids, speed_rpm, "
                              "model_version, signature) VALUES (:a, '2026-11-02 11:00:00', 'auto', :ids, 3000.0, "
                              "'v0002', :sig)"), {"a": asset, "ids": ids, "sig": sig})
    migrate(engine, "v0008")
    sessions = init_db(engine)
    with sessions() as s:
        got = {(m.asset_id, m.diagnosis_id): m.signature for m in s.scalars(select(AssetBaselineRecording))}
    # a1 and a4: one recording, the baseline's signature (a4's diagnosis is gone); a2: both diagnoses' own;
    # a3: one signature trimmed, so none (the baseline keeps working from its average)
    assert got == {("a1", 1): {"avg": 1}, ("a2", 2): {"speed_rpm": 3001.0}, ("a2", 3): {"speed_rpm": 3002.0},
                   ("a4", 99): {"avg": 4}}
    migrate(engine, "v0007")
    assert "asset_baseline_recordings" not in inspect(engine).get_table_names()
    with engine.connect() as conn:
        assert conn.execute(text("SELECT COUNT(*) FROM asset_baselines")).scalar_one() == 4
    migrate(engine)
    assert current_revision(engine) == "v0010"
    with sessions() as s:
        assert s.scalar(select(func.count()).select_from(AssetBaselineRecording)) == 4
    engine.dispose()


def test_v0010_asset_startups_up_and_down(database_url):
    """v0010 adds the asset_startups table (an asset's start-ups as evidence, issue 46); down removes it and
    leaves every other row; up again gives an empty table that takes a start-up."""
    from rotordiag.service.core.db import AssetStartup

    engine = make_engine(database_url)
    migrate(engine, "v0007")
    assert "asset_startups" not in inspect(engine).get_table_names()
    with engine.begin() as conn:   # a diagnosis written by version v0007's code
        conn.execute(text("INSERT INTO asset_diagnoses (asset_id, created_at, model_version, severity, verdict, "
                          "key_features) VALUES ('u9', '2026-11-01 12:00:00', 'v1', 'aligned', '{}', '{}')"))
    sessions = init_db(engine)
    assert current_revision(engine) == "v0010"
    evidence = {"criticals": {"b2@45": 1150.0}, "half_rise_rpm": {"2": 800.0}, "top_um": {"2": [1.0, 60.0]},
                "clearance_um": {"2": 350.0}, "speed_range_rpm": [300.0, 2000.0]}
    with sessions.begin() as s:
        s.add(AssetStartup(asset_id="u9", is_baseline=True, evidence=evidence, summary={"kind": "run-up"},
                           recorded_at=dt.datetime(2026, 3, 1, 6, 0, tzinfo=dt.UTC)))
    with sessions() as s:
        row = s.scalars(select(AssetStartup)).one()
        assert row.evidence == evidence and row.is_baseline is True and row.note is None
        assert row.recorded_at == dt.datetime(2026, 3, 1, 6, 0, tzinfo=dt.UTC)
    migrate(engine, "v0007")
    assert current_revision(engine) == "v0007"
    assert "asset_startups" not in inspect(engine).get_table_names()
    with engine.connect() as conn:
        assert conn.execute(text("SELECT COUNT(*) FROM asset_diagnoses WHERE asset_id = 'u9'")).scalar_one() == 1
    migrate(engine)
    assert current_revision(engine) == "v0010"
    with sessions() as s:
        assert s.scalar(select(func.count()).select_from(AssetStartup)) == 0
    engine.dispose()


def test_migrated_schema_equals_the_models(database_url):
    """Alembic's autogenerate comparison finds nothing between the migrated database and the models."""
    from alembic.autogenerate import compare_metadata
    from alembic.runtime.migration import MigrationContext

    engine = make_engine(database_url)
    migrate(engine)
    with engine.connect() as conn:
        diff = compare_metadata(MigrationContext.configure(conn), Base.metadata)
    assert diff == [], diff
    engine.dispose()


def test_replicas_starting_together_migrate_once(postgres):
    """Four 'replicas' migrating one empty PostgreSQL database at once all succeed (advisory lock)."""
    url = postgres.new_database()
    errors: list[BaseException] = []

    def start() -> None:
        try:
            e = make_engine(url)
            init_db(e)
            e.dispose()
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=start) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert errors == []
    assert current_revision(make_engine(url)) == head_revision()


def test_copy_sqlite_store_into_postgresql(tmp_path, postgres):
    src = make_engine(_old_sqlite(tmp_path / "old.sqlite3"))
    dst_url = postgres.new_database()
    dst = make_engine(dst_url)
    copied = copy_store(src, dst)
    assert copied == {"alarm_events": 0, "asset_baseline_recordings": 2, "asset_baselines": 1, "asset_diagnoses": 3, "asset_settings": 1, "asset_startups": 0, "jobs": 2,
                      "service_probe": 0, "webhook_deliveries": 0, "webhooks": 0}
    sessions = init_db(dst)
    _check_reference_rows(sessions)
    with sessions.begin() as s:   # the id sequence continues after the copied rows
        row = AssetDiagnosis(asset_id="unit-8", model_version="v0001", severity="none", verdict={}, key_features={})
        s.add(row)
        s.flush()
        assert row.id == 4
    with pytest.raises(CopyError, match="already holds rows"):
        copy_store(src, dst)
    with sessions() as s:
        assert s.scalar(select(func.count()).select_from(AssetDiagnosis)) == 4


def test_db_copy_command(tmp_path, postgres):
    from typer.testing import CliRunner

    from rotordiag.cli import app

    src = _old_sqlite(tmp_path / "old.sqlite3")
    dst = postgres.new_database()
    runner = CliRunner()
    r = runner.invoke(app, ["db", "copy", dst, "--from", src])
    assert r.exit_code == 0, r.output
    assert "asset_diagnoses: 3 row(s)" in r.output
    r = runner.invoke(app, ["db", "current", "--url", dst])
    assert r.exit_code == 0 and "database: v0010" in r.output
    r = runner.invoke(app, ["db", "copy", dst, "--from", src])
    assert r.exit_code == 2 and "already holds rows" in r.output


def test_baseline_recordings_added_and_removed_on_each_backend(database_url):
    """Adding and removing baseline recordings through service.baseline on SQLite and PostgreSQL: the asset's own
    thresholds appear at 3 recordings and go at 2; on PostgreSQL two recordings added at once are both kept (the
    baseline row is locked while it is rewritten)."""
    from types import SimpleNamespace

    from rotordiag.service.baseline import add_recording, remove_recording
    from tests.test_baseline_change import _sig

    engine = make_engine(database_url)
    sessions = init_db(engine)
    with sessions.begin() as s:
        for i in range(1, 6):
            s.add(AssetDiagnosis(id=i, asset_id="u9", model_version="v0001", severity="aligned", verdict={},
                                 key_features={}, speed_rpm=1800.0, signature=_sig(seed=100 + i)))
    state = SimpleNamespace(sessions=sessions, settings=None)
    assert add_recording(state, "u9", 1)["thresholds_basis"]["reason"] == "too_few_recordings"
    add_recording(state, "u9", 2)
    b = add_recording(state, "u9", 3)
    assert b["diagnosis_ids"] == [1, 2, 3] and b["repeatability"]["n_recordings"] == 3
    b = remove_recording(state, "u9", 2)
    assert b["diagnosis_ids"] == [1, 3] and b["repeatability"] is None and b["thresholds_basis"]["basis"] == "fleet"
    if engine.dialect.name == "postgresql":
        errors: list[BaseException] = []

        def add(i: int) -> None:
            try:
                add_recording(state, "u9", i)
            except BaseException as exc:  # noqa: BLE001 - reported below
                errors.append(exc)

        threads = [threading.Thread(target=add, args=(i,)) for i in (4, 5)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(60)
        assert errors == []
        with sessions() as s:
            assert sorted(s.get(AssetBaseline, "u9").diagnosis_ids) == [1, 3, 4, 5]
            assert s.scalar(select(func.count()).select_from(AssetBaselineRecording)) == 4
    engine.dispose()
