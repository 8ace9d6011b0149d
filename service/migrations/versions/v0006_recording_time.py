"""Recording time, operating-state tags and event notes of a stored diagnosis (issue 45, item 2):
``asset_diagnoses.recorded_at``, ``tags`` and ``note``.

Revision ID: v0006
Revises: v0005
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "v0006"
down_revision = "v0005"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column("asset_diagnoses", sa.Column("recorded_at", sa.DateTime(), nullable=True))
    op.add_column("asset_diagnoses", sa.Column("tags", sa.JSON(), nullable=True))
    op.add_column("asset_diagnoses", sa.Column("note", sa.Text(), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("asset_diagnoses") as batch:
        batch.drop_column("note")
        batch.drop_column("tags")
        batch.drop_column("recorded_at")
