"""The simulated arm: safe-circle moves, guarded moves along sensing paths, touches.

:class:`SimulatedArm` implements :class:`hardware_sim.protocol.Probe` on top of
:class:`hardware_sim.world.World`. One probe (thesis ch. 5):

1. move along the safe circle from the sensor's place to the path origin;
2. guarded move along the path until the contact force passes the threshold
   (first contact found by ray casting the true outline), or to the path end (a miss);
3. with `recalibrate`: back off, zero the sensor at no load, touch again slowly
   (the thesis' routine against channel drift); read the sensor;
4. retreat along the path to its origin (a miss ending on the circle stays there).

Error sources, each a parameter of :class:`ArmParams`:

- compliance: the hand keeps moving after the tip stops at the surface; the
  joint readings report the hand, so the measured tip lies ``F / k`` past the
  contact along the path (F the true peak force, k the stiffness);
- wrist backlash: the finger (vertical, so its tip does not move) turns within
  the play; the sensor frame is off by up to half the play, which turns the
  measured normal;
- thermal drift: the potentiometers warm with use (``h = 1 - (1 - h) exp(-dt /
  heat_time)`` while powered) and the readings drift by ``h`` times a fixed
  offset (position and wrist angle); above `cooldown_at` the arm pauses to cool
  (``h = h exp(-dt / cool_time)``) before the next probe;
- vertex contacts: a hit within `vertex_zone` of a protruding vertex slides off
  onto one of its two faces (the thesis' compliant E2, ch. 5.1);
- the fingertip ball (`tip_radius`): the contact is the tip centre moved back by
  the radius along the measured normal, so the normal error moves the point too;
  with `report_centre` the ball's centre runs along the path and stops where it
  meets the outline grown by the radius (:meth:`World.ball_contact`), and the
  arm reports that centre, as a controller does: the service moves it back
  (DESIGN §4.14);
- `reading_noise`: joint-reading noise, uniform in a disk of that radius.

Frames and units: world frame, lengths in the object files' unit (mm for the
shipped sets), forces in N, stiffness in N per length unit, angles in radians
(counter-clockwise), times in seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hardware_sim.protocol import ProbeResult
from hardware_sim.sensor import ForceSensor, Press
from hardware_sim.world import World
from planner.geometry import LENGTH_SLACK
from planner.types import Contact, Observation, SensingPath

__all__ = ["ArmParams", "SimulatedArm", "slide_off_vertex"]


@dataclass(frozen=True)
class ArmParams:
    """Arm parameters (world length unit L, N, s, rad); defaults are an ideal arm.

    Motion: `speed` (L/s) along the safe circle, `approach_speed` (L/s) of the
    guarded move, `touch_speed` (L/s) of the recalibrated second touch, `backoff`
    (L) before zeroing, `recalibrate` (run the back off / zero / touch routine).
    Contact: `threshold` (N), `stiffness` (N/L, inf = rigid; the force grows at
    ``stiffness x speed`` N/s after contact), `tip_radius` (L), `report_centre`
    (report the ball's centre, not the surface point), `vertex_zone` (L).
    Errors: `backlash` (rad, total wrist play), `thermal_position` (L) and
    `thermal_angle` (rad) of the joint readings at full heat, `heat_time`,
    `cool_time` (s), `cooldown_at`, `cooldown_to` (heat levels in [0, 1]),
    `reading_noise` (L).
    """

    speed: float = 100.0
    approach_speed: float = 20.0
    touch_speed: float = 2.0
    backoff: float = 2.0
    recalibrate: bool = False
    threshold: float = 3.0
    stiffness: float = math.inf
    tip_radius: float = 0.0
    report_centre: bool = False
    vertex_zone: float = 0.0
    backlash: float = 0.0
    thermal_position: float = 0.0
    thermal_angle: float = 0.0
    heat_time: float = 600.0
    cool_time: float = 300.0
    cooldown_at: float = 0.8
    cooldown_to: float = 0.1
    reading_noise: float = 0.0

    def __post_init__(self) -> None:
        for name in ("speed", "approach_speed", "touch_speed", "threshold", "stiffness"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0")
        if not 0 <= self.cooldown_to < self.cooldown_at <= 1:
            raise ValueError("need 0 <= cooldown_to < cooldown_at <= 1")


def slide_off_vertex(
    world: World,
    point: np.ndarray,
    face: int,
    direction: np.ndarray,
    zone: float,
    rng: np.random.Generator,
    height: float | None = None,
) -> tuple[np.ndarray, int]:
    """Where a compliant tip comes to rest after hitting `face` at `point` (world).

    Within `zone` of a protruding vertex the tip flops onto the neighbouring face
    with probability ``|d.n_B| / (|d.n_A| + |d.n_B|) (1 - s / zone)`` (s the
    distance to the vertex, d the path direction), resting at a distance uniform
    in [0, zone] from the vertex along that face; otherwise it stays. A face that
    turns away from the path (d.n_B >= 0) cannot catch the tip. Faces are those
    of the layer at the path's probing `height`. Returns the rest point and its
    face index.
    """
    if zone <= 0:
        return point, face
    start, end, normal = world.posed_faces(height)
    for vertex, neighbour_end in ((start[face], "end"), (end[face], "start")):
        s = float(np.hypot(*(point - vertex)))
        if s > zone:
            continue
        # the neighbour shares this vertex: its end (or start) is our start (or end)
        other = end if neighbour_end == "end" else start
        near = np.flatnonzero(np.hypot(*(other - vertex).T) <= LENGTH_SLACK * max(1.0, zone))
        near = near[near != face]
        if not len(near):
            continue
        b = int(near[0])
        # protruding vertex: the ring turns left there (material on the left of every edge)
        e_in = (end[face] - start[face]) if neighbour_end == "start" else (end[b] - start[b])
        e_out = (end[b] - start[b]) if neighbour_end == "start" else (end[face] - start[face])
        if e_in[0] * e_out[1] - e_in[1] * e_out[0] <= 0:
            continue
        catch_a, catch_b = abs(direction @ normal[face]), -float(direction @ normal[b])
        if catch_b <= 0:
            continue
        # P(slide onto B) = |d.n_B| / (|d.n_A| + |d.n_B|) * (1 - s / zone)
        if rng.random() >= catch_b / (catch_a + catch_b) * (1.0 - s / zone):
            continue
        along = end[b] - start[b]
        length = float(np.hypot(*along))
        away = along / length if neighbour_end == "start" else -along / length
        rest = vertex + min(rng.uniform(0.0, zone), 0.5 * length) * away
        return rest, b
    return point, face


class SimulatedArm:
    """An arm carrying a touch sensor around one :class:`World` (a :class:`Probe`).

    Stateful like the hardware: the sensor's place on the safe circle (`angle`,
    rad about the centre), the rig clock (s), the heat of the joint
    potentiometers (0..1). All randomness comes from `rng`.
    """

    def __init__(
        self,
        world: World,
        params: ArmParams,
        sensor: ForceSensor,
        rng: np.random.Generator,
        start_angle: float = 0.0,
    ) -> None:
        self.world = world
        self.params = params
        self.sensor = sensor
        self.rng = rng
        self.angle = float(start_angle)
        self.clock = 0.0
        self.heat = 0.0
        self.touches = 0
        self.last_press: Press | None = None
        # fixed direction of the joint-reading drift, and the sign of the wrist drift
        a = rng.uniform(-math.pi, math.pi)
        self._thermal_dir = np.array([math.cos(a), math.sin(a)])
        self._thermal_sign = float(rng.choice([-1.0, 1.0]))
        # after the first zero the routine keeps the sensor calibrated
        self.sensor.zero()

    # -- state --------------------------------------------------------------------
    @property
    def position(self) -> tuple[float, float]:
        """The sensor's place on the safe circle (world frame)."""
        c, r = np.asarray(self.world.workspace.center), self.world.workspace.radius
        p = c + r * np.array([math.cos(self.angle), math.sin(self.angle)])
        return (float(p[0]), float(p[1]))

    def _run(self, seconds: float) -> None:
        """Powered time: the clock and the sensor advance, the potentiometers warm."""
        self.clock += seconds
        # h = 1 - (1 - h) exp(-dt / heat_time)
        self.heat = 1.0 - (1.0 - self.heat) * math.exp(-seconds / self.params.heat_time)

    def cool_down(self) -> float:
        """Switch off until the heat falls to `cooldown_to`; returns the pause (s)."""
        p = self.params
        if self.heat <= p.cooldown_to:
            return 0.0
        # h exp(-t / cool_time) = cooldown_to  =>  t = cool_time ln(h / cooldown_to)
        pause = p.cool_time * math.log(self.heat / max(p.cooldown_to, 1e-12))
        self.heat = p.cooldown_to
        self.clock += pause
        self.sensor.advance(pause)
        return pause

    def thermal_error(self) -> tuple[np.ndarray, float]:
        """Current joint-reading error: tip position offset (L) and wrist angle (rad)."""
        p = self.params
        return (
            self.heat * p.thermal_position * self._thermal_dir,
            self.heat * p.thermal_angle * self._thermal_sign,
        )

    # -- the probe ------------------------------------------------------------------
    def execute(self, path: SensingPath) -> ProbeResult:
        """Run one sensing path; see the module docstring for the steps."""
        p = self.params
        t0 = self.clock
        if self.heat > p.cooldown_at:
            self.cool_down()
        distance = 0.0
        centre = np.asarray(self.world.workspace.center)
        radius = self.world.workspace.radius
        origin, d = np.asarray(path.origin), np.asarray(path.direction)
        rel = origin - centre
        target = math.atan2(rel[1], rel[0])
        # arc along the circle, R |wrap(target - angle)|, plus any radial step to the origin
        turn = (target - self.angle + math.pi) % (2 * math.pi) - math.pi
        move = radius * abs(turn) + abs(float(np.hypot(*rel)) - radius)
        distance += move
        self._moved(move / p.speed)
        self.angle = target
        ball = p.report_centre and p.tip_radius > 0
        if ball:
            stop = self.world.ball_contact(path, p.tip_radius)
            hit = None if stop is None else (stop[0], stop[2])  # the centre stops there
        else:
            hit = self.world.first_contact(path)
        if hit is None:
            distance += path.length
            self._moved(path.length / p.approach_speed)
            end = origin + path.length * d
            rel_end = end - centre
            if abs(float(np.hypot(*rel_end)) - radius) <= 1e-6 * radius:
                self.angle = math.atan2(rel_end[1], rel_end[0])
            else:  # back along the path to its origin
                distance += path.length
                self._moved(path.length / p.approach_speed)
            self.touches += 1
            return ProbeResult(Observation(path, None), distance, self.clock - t0)
        point, face = hit
        approach = float((point - origin) @ d)
        distance += approach
        self._moved(approach / p.approach_speed)
        if ball:
            point = stop[1]  # the surface point the ball touches
        point, face = slide_off_vertex(
            self.world, point, face, d, p.vertex_zone, self.rng, path.height
        )
        normal = self.world.posed_faces(path.height)[2][face]
        contact, extra, deflection = self._touch(point, normal, d)
        # the hand went `deflection` past the contact; retreat along the path to its origin
        distance += extra + 2 * deflection + approach
        self._moved((approach + deflection) / p.approach_speed)
        self.touches += 1
        return ProbeResult(
            Observation(path, contact),
            distance,
            self.clock - t0,
            (float(point[0]), float(point[1])),
            (float(normal[0]), float(normal[1])),
        )

    def _moved(self, seconds: float) -> None:
        self._run(seconds)
        self.sensor.advance(seconds)

    def _touch(
        self, point: np.ndarray, normal: np.ndarray, d: np.ndarray
    ) -> tuple[Contact, float, float]:
        """Press on the surface at `point` (true outward `normal`) coming along `d`;
        returns the measured contact, the distance travelled by the recalibration
        routine and the hand's final deflection past the contact (L)."""
        p = self.params
        # wrist: commanded along the path; the finger sits somewhere in the play
        wrist = math.atan2(d[1], d[0])
        play = self.rng.uniform(-p.backlash / 2, p.backlash / 2)
        offset, wrist_drift = self.thermal_error()
        true_wrist = wrist + play
        # the object pushes the tip along its outward normal; sensor frame = R(-psi) world
        c, s = math.cos(true_wrist), math.sin(true_wrist)
        force_dir = np.array([c * normal[0] + s * normal[1], -s * normal[0] + c * normal[1]])
        extra = 0.0
        # the force grows at stiffness x speed (N/s) once the tip is stopped by the object
        press = self.sensor.press(force_dir, p.threshold, p.stiffness * p.approach_speed)
        self._run(press.duration)
        if p.recalibrate:
            # back off, zero at no load, touch again slowly (thesis ch. 5)
            back = p.backoff + press.peak / p.stiffness
            self._moved(back / p.approach_speed)
            self._run(self.sensor.zero())
            self._moved(p.backoff / p.touch_speed)
            press = self.sensor.press(force_dir, p.threshold, p.stiffness * p.touch_speed)
            self._run(press.duration)
            extra += back + p.backoff
        self.last_press = press
        read_wrist = wrist + wrist_drift
        c, s = math.cos(read_wrist), math.sin(read_wrist)
        m = press.direction
        measured = np.array([c * m[0] - s * m[1], s * m[0] + c * m[1]])
        # hand reading = tip centre + deflection F/k along the path + drift + noise
        deflection = press.peak / p.stiffness
        centre = point + p.tip_radius * normal
        r = p.reading_noise * math.sqrt(self.rng.random())
        a = self.rng.uniform(-math.pi, math.pi)
        noise = r * np.array([math.cos(a), math.sin(a)])
        reading = centre + deflection * d + offset + noise
        # contact = tip centre - tip_radius x measured normal (or the centre itself)
        sensed = reading if p.report_centre else reading - p.tip_radius * measured
        contact = Contact(
            (float(sensed[0]), float(sensed[1])), (float(measured[0]), float(measured[1]))
        )
        return contact, extra, deflection
