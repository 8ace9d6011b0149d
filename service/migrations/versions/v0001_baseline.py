"""The schema as the service had it before Alembic (jobs, asset diagnoses, baselines, alarm settings).

A database made by that service (``create_all`` plus its add-missing-columns step, no
``alembic_version`` table) is adopted in place: tables that exist are kept with their rows,
and the nullable columns an even older version lacked are added, as that step did.

Revision ID: v0001
Revises:
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "v0001"
down_revision = None
branch_labels = None
depends_on = None


def _tables() -> list[sa.Table]:
    md = sa.MetaData()
    return [
        sa.Table(
            "jobs", md,
            sa.Column("id", sa.String(36), primary_key=True),
            sa.Column("kind", sa.String(16), nullable=False, index=True),
            sa.Column("status", sa.String(16), nullable=False, index=True),
            sa.Column("params", sa.JSON(), nullable=False),
            sa.Column("progress", sa.Float(), nullable=False),
            sa.Column("stage", sa.String(64), nullable=False),
            sa.Column("message", sa.Text(), nullable=False),
            sa.Column("result", sa.JSON(), nullable=True),
            sa.Column("error", sa.Text(), nullable=True),
            sa.Column("attempts", sa.Integer(), nullable=False),
            sa.Column("created_at", sa.DateTime(), nullable=False),
            sa.Column("started_at", sa.DateTime(), nullable=True),
            sa.Column("finished_at", sa.DateTime(), nullable=True),
            sa.Column("updated_at", sa.DateTime(), nullable=False),
        ),
        sa.Table(
            "asset_diagnoses", md,
            sa.Column("id", sa.Integer(), primary_key=True, autoincrement=True),
            sa.Column("asset_id", sa.String(128), nullable=False, index=True),
            sa.Column("plant", sa.String(128), nullable=True),
            sa.Column("created_at", sa.DateTime(), nullable=False, index=True),
            sa.Column("model_version", sa.String(128), nullable=False),
            sa.Column("severity", sa.String(32), nullable=False),
            sa.Column("misalignment", sa.Float(), nullable=True),
            sa.Column("misalignment_low", sa.Float(), nullable=True),
            sa.Column("misalignment_high", sa.Float(), nullable=True),
            sa.Column("speed_rpm", sa.Float(), nullable=True),
            sa.Column("ood", sa.Boolean(), nullable=True),
            sa.Column("verdict", sa.JSON(), nullable=False),
            sa.Column("key_features", sa.JSON(), nullable=False),
            sa.Column("signature", sa.JSON(none_as_null=True), nullable=True),
            sa.Column("change", sa.JSON(none_as_null=True), nullable=True),
            sa.Column("alarm", sa.Boolean(), nullable=True),
        ),
        sa.Table(
            "asset_baselines", md,
            sa.Column("asset_id", sa.String(128), primary_key=True),
            sa.Column("created_at", sa.DateTime(), nullable=False),
            sa.Column("source", sa.String(16), nullable=False),
            sa.Column("diagnosis_ids", sa.JSON(), nullable=False),
            sa.Column("recorded_at", sa.DateTime(), nullable=True),
            sa.Column("speed_rpm", sa.Float(), nullable=True),
            sa.Column("model_version", sa.String(128), nullable=False),
            sa.Column("signature", sa.JSON(), nullable=False),
            sa.Column("repeatability", sa.JSON(), nullable=True),
        ),
        sa.Table(
            "asset_settings", md,
            sa.Column("asset_id", sa.String(128), primary_key=True),
            sa.Column("thresholds", sa.JSON(), nullable=False),
            sa.Column("updated_at", sa.DateTime(), nullable=False),
        ),
    ]


def upgrade() -> None:
    bind = op.get_bind()
    insp = sa.inspect(bind)
    for table in _tables():
        if not insp.has_table(table.name):
            table.create(bind)
            continue
        have = {c["name"] for c in insp.get_columns(table.name)}
        for col in table.columns:
            if col.name in have:
                continue
            if not col.nullable:
                raise RuntimeError(f"database table {table.name} lacks the required column {col.name}; "
                                   "it cannot be added in place")
            op.add_column(table.name, sa.Column(col.name, col.type, nullable=True))


def downgrade() -> None:
    for table in reversed(_tables()):
        op.drop_table(table.name)
