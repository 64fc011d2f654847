"""The `tactile` command line and the tools that wire the planner, the service and the simulator
together: demo, simulate, bench, calibration, load test, latency, client generation (DESIGN §7)."""
