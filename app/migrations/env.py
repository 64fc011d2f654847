"""alembic's entry: migrations run on the connection (and transaction) the store gives."""

from __future__ import annotations

from alembic import context

connection = context.config.attributes.get("connection")
if connection is None:
    raise RuntimeError("the store runs its migrations itself (app.migrations.upgrade)")
context.configure(connection=connection, transactional_ddl=True, render_as_batch=True)
with context.begin_transaction():
    context.run_migrations()
