"""The HTTP service (DESIGN §6): thin routes over the planner, event-sourced sessions in a store."""
