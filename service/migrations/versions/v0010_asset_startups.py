"""An asset's start-ups and coast-downs as evidence (issue 46, item 4): the ``asset_startups`` table — each
uploaded run's evidence (1X criticals, coupling-end centreline rise) and summary, one of them the asset's baseline
start-up. The service keeps no waveform: a later start-up is compared with the baseline's stored evidence.

Revision ID: v0010
Revises: v0008
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "v0010"
down_revision = "v0008"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "asset_startups",
        sa.Column("id", sa.Integer(), primary_key=True, autoincrement=True),
        sa.Column("asset_id", sa.String(128), nullable=False),
        sa.Column("created_at", sa.DateTime(), nullable=False),
        sa.Column("recorded_at", sa.DateTime(), nullable=True),
        sa.Column("is_baseline", sa.Boolean(), nullable=False),
        sa.Column("evidence", sa.JSON(), nullable=False),
        sa.Column("summary", sa.JSON(), nullable=False),
        sa.Column("note", sa.Text(), nullable=True),
    )
    op.create_index("ix_asset_startups_asset_id", "asset_startups", ["asset_id", "id"])


def downgrade() -> None:
    op.drop_index("ix_asset_startups_asset_id", table_name="asset_startups")
    op.drop_table("asset_startups")
