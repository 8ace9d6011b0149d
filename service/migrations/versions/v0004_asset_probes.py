"""The asset's probe configuration (issue 45): ``asset_settings.probes``, the reader options every upload to
that asset uses (``PUT /assets/{id}/probes``).

A database that already has the column (added in place by a version between issue 45 and Alembic) keeps it.

Revision ID: v0004
Revises: v0003
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "v0004"
down_revision = "v0003"
branch_labels = None
depends_on = None


def upgrade() -> None:
    have = {c["name"] for c in sa.inspect(op.get_bind()).get_columns("asset_settings")}
    if "probes" not in have:
        op.add_column("asset_settings", sa.Column("probes", sa.JSON(), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("asset_settings") as batch:
        batch.drop_column("probes")
