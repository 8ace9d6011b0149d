"""The recordings of an asset's baseline (issue 48, item 4): ``asset_baseline_recordings``, one row per recording a
baseline is made of, with its own signature, so the baseline and its per-asset change thresholds can be recomputed
when a recording is added or removed.

Existing baselines get their rows from the diagnoses they name when every one of them still keeps its signature
(a one-recording baseline takes the baseline's own signature, which is that recording's); a baseline of several
recordings whose signatures were trimmed gets none and keeps working as it is (adding or removing a recording then
asks for a new baseline).

Revision ID: v0008
Revises: v0007
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "v0008"
down_revision = "v0007"
branch_labels = None
depends_on = None


def upgrade() -> None:
    table = op.create_table(
        "asset_baseline_recordings",
        sa.Column("asset_id", sa.String(128), primary_key=True),
        sa.Column("diagnosis_id", sa.Integer(), primary_key=True, autoincrement=False),
        sa.Column("added_at", sa.DateTime(), nullable=False),
        sa.Column("recorded_at", sa.DateTime(), nullable=True),
        sa.Column("speed_rpm", sa.Float(), nullable=True),
        sa.Column("model_version", sa.String(128), nullable=False),
        sa.Column("signature", sa.JSON(), nullable=False),
    )
    bind = op.get_bind()
    baselines = sa.table("asset_baselines", sa.column("asset_id", sa.String), sa.column("created_at", sa.DateTime),
                         sa.column("diagnosis_ids", sa.JSON), sa.column("signature", sa.JSON),
                         sa.column("model_version", sa.String), sa.column("speed_rpm", sa.Float),
                         sa.column("recorded_at", sa.DateTime))
    diagnoses = sa.table("asset_diagnoses", sa.column("id", sa.Integer), sa.column("asset_id", sa.String),
                         sa.column("created_at", sa.DateTime), sa.column("speed_rpm", sa.Float),
                         sa.column("model_version", sa.String), sa.column("signature", sa.JSON))
    rows = []
    for b in bind.execute(sa.select(baselines)).mappings().all():
        ids = [int(i) for i in (b["diagnosis_ids"] or []) if isinstance(i, int)]
        if not ids:
            continue
        found = {d["id"]: d for d in bind.execute(sa.select(diagnoses).where(
            diagnoses.c.id.in_(ids), diagnoses.c.asset_id == b["asset_id"])).mappings().all()}
        if len(ids) == 1:
            d = found.get(ids[0])
            rows.append({"asset_id": b["asset_id"], "diagnosis_id": ids[0], "added_at": b["created_at"],
                         "recorded_at": d["created_at"] if d is not None else b["recorded_at"],
                         "speed_rpm": b["speed_rpm"], "model_version": b["model_version"],
                         "signature": b["signature"]})
        elif all(i in found and found[i]["signature"] is not None for i in ids):
            rows += [{"asset_id": b["asset_id"], "diagnosis_id": i, "added_at": b["created_at"],
                      "recorded_at": found[i]["created_at"], "speed_rpm": found[i]["speed_rpm"],
                      "model_version": found[i]["model_version"], "signature": found[i]["signature"]} for i in ids]
    if rows:
        op.bulk_insert(table, rows)


def downgrade() -> None:
    op.drop_table("asset_baseline_recordings")
