"""The one boundary between the planner side and (simulated) hardware.

A :class:`Probe` executes a straight sensing path and answers with a
:class:`ProbeResult`: the observation the planner consumes (a contact with its
measured point and outward normal, or a miss), plus what the move cost (travel
distance along the safe circle and the path, and wall-clock time of the rig).
Everything is in the world frame: lengths in the object files' unit (mm for the
shipped sets), angles in radians counter-clockwise, times in seconds.

Implementations: :class:`hardware_sim.arm.SimulatedArm` (arm + strain-gauge
sensor on top of :class:`hardware_sim.world.World`). A real robot driver would
implement the same two members.

>>> from hardware_sim.presets import build_arm
>>> from hardware_sim.world import World
>>> from planner.models.library import object_from_dict
>>> from planner.types import Pose, SensingPath, Workspace
>>> outline = [[-10, -10], [10, -10], [10, 10], [-10, 10]]
>>> square = object_from_dict({"name": "sq", "outline": outline})
>>> world = World(square, 0, Pose(0.0, 0.0, 0.0), Workspace((0, 0), 100))
>>> probe: Probe = build_arm(world, "ideal", seed=0)
>>> result = probe.execute(SensingPath((100.0, 0.0), (-1.0, 0.0), 200.0))
>>> result.observation.contact.point, result.observation.contact.normal
((10.0, 0.0), (1.0, 0.0))
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from planner.types import Observation, SensingPath

__all__ = ["Probe", "ProbeResult"]


@dataclass(frozen=True)
class ProbeResult:
    """What one executed sensing path gave.

    `observation`: the path and the measured contact (None: a miss), world frame.
    `distance`: length travelled by the sensor tip for this probe (arc along the
    safe circle to the path origin, approach, recalibration back-off and return,
    retreat), object-file length unit. `time`: rig time spent, seconds, including
    any cool-down pause. `true_point` / `true_normal`: the real contact on the
    object (world frame) for diagnostics and tests; None on a miss or when the
    hardware cannot know it.
    """

    observation: Observation
    distance: float
    time: float
    true_point: tuple[float, float] | None = None
    true_normal: tuple[float, float] | None = None

    @property
    def hit(self) -> bool:
        return self.observation.contact is not None


@runtime_checkable
class Probe(Protocol):
    """Executes sensing paths: the whole hardware surface the client needs."""

    @property
    def position(self) -> tuple[float, float]:
        """The sensor's current place on the safe circle (world frame)."""
        ...

    def execute(self, path: SensingPath) -> ProbeResult:
        """Move along the safe circle to `path.origin`, then along the path until the
        contact force passes the threshold (a contact) or the path ends (a miss)."""
        ...
