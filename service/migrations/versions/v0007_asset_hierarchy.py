"""Where an asset sits (issue 45, item 2): ``asset_settings.site``, ``unit`` and ``train``.

Revision ID: v0007
Revises: v0006
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "v0007"
down_revision = "v0006"
branch_labels = None
depends_on = None


def upgrade() -> None:
    for name in ("site", "unit", "train"):
        op.add_column("asset_settings", sa.Column(name, sa.String(128), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("asset_settings") as batch:
        for name in ("train", "unit", "site"):
            batch.drop_column(name)
