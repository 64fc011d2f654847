"""Sessions and objects belong to the client whose key created them.

Objects are named per client: the key of ``objects`` becomes (owner, name), so two
clients may each register a ``bracket``. Rows written before this migration belong
to the anonymous owner ``''`` (an open service, or the single ``api_key``).

Revision ID: 0003
Revises: 0002
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("sessions") as batch:
        batch.add_column(sa.Column("owner", sa.Text, nullable=False, server_default=""))
    # a new primary key: a new table, the same on SQLite and PostgreSQL
    op.create_table(
        "objects_owned",
        sa.Column("owner", sa.Text, nullable=False, server_default=""),
        sa.Column("name", sa.Text, nullable=False),
        sa.Column("body", sa.Text, nullable=False),
        sa.Column("created_at", sa.Float, nullable=False),
        sa.PrimaryKeyConstraint("owner", "name", name="objects_owner_name_pkey"),
    )
    op.execute(
        "INSERT INTO objects_owned (owner, name, body, created_at) "
        "SELECT '', name, body, created_at FROM objects"
    )
    op.drop_table("objects")
    op.rename_table("objects_owned", "objects")


def downgrade() -> None:
    """Back to one namespace: only the anonymous owner's objects are kept."""
    op.create_table(
        "objects_shared",
        sa.Column("name", sa.Text, primary_key=True),
        sa.Column("body", sa.Text, nullable=False),
        sa.Column("created_at", sa.Float, nullable=False),
    )
    op.execute(
        "INSERT INTO objects_shared (name, body, created_at) "
        "SELECT name, body, created_at FROM objects WHERE owner = ''"
    )
    op.drop_table("objects")
    op.rename_table("objects_shared", "objects")
    with op.batch_alter_table("sessions") as batch:
        batch.drop_column("owner")
