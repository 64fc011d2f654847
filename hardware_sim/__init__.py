"""Simulated hardware (DESIGN §5): world, arm, strain-gauge sensor, and the closed-loop clients that
drive a recognition in process or over HTTP."""
