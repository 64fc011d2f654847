"""Outcome model (DESIGN §4.11) and candidate paths (§4.10).

The vectorized caster is checked against a slow per-ray reference written with
plain loops (and shapely for the first hit) on random configurations; the
tolerance rules are checked one by one on hand-built scenes.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely
from hypothesis import event, given, settings
from hypothesis import strategies as st

from planner.geometry import wrap_angle
from planner.models.outlines import make_stable_pose
from planner.planning import matching
from planner.planning.bitsets import (
    IntervalUnions,
    SurvivorTable,
    close_ends,
    pack_bits,
    popcount,
    sorted_count,
    to_int,
    transpose_bits,
    unpack_bits,
    weighted_count,
)
from planner.planning.candidate_generation import CandidateConfig, generate_candidates
from planner.planning.candidates import Candidates
from planner.planning.confusability import class_survivors, confusability, survivor_table
from planner.planning.intersection_aims import _grid_depth
from planner.planning.matching import SLOTS, Slots, slots_match
from planner.planning.outcomes import OutcomeConfig, Outcomes, predict_outcomes
from planner.planning.posed_set import contains_points, pose_hypotheses
from planner.types import (
    ErrorBound,
    Hypothesis,
    ObjectModel,
    Pose,
    SensingPath,
    SensorBounds,
    Workspace,
)

SHAPES = {
    "square": ([[-20, -20], [20, -20], [20, 20], [-20, 20]], []),
    "triangle": ([[30, 0], [-15, 26], [-15, -26]], []),
    "ell": ([[0, 0], [40, 0], [40, 12], [12, 12], [12, 30], [0, 30]], []),
    "frame": (
        [[-20, -20], [20, -20], [20, 20], [-20, 20]],
        [[[-10, -10], [-10, 10], [10, 10], [10, -10]]],
    ),
}
MODELS = {
    name: ObjectModel(name, (make_stable_pose(outline, holes),))
    for name, (outline, holes) in SHAPES.items()
}
WORKSPACE = Workspace((0.0, 0.0), 100.0)


def hyp(
    name: str,
    x: float,
    y: float,
    theta: float = 0.0,
    cls: int = 0,
    p: float = 1.0,
    eps_t: float = 0.0,
    rotation: float = 0.0,
) -> Hypothesis:
    return Hypothesis(
        name, 0, (), Pose(x, y, theta), ErrorBound(0.0, rotation, eps_t), p, equivalence_class=cls
    )


def cast(hyps, origins, directions, lengths, sensor=None, config=None):
    sensor = sensor or SensorBounds()
    posed = pose_hypotheses(hyps, MODELS)
    out = predict_outcomes(
        posed,
        np.asarray(origins, float),
        np.asarray(directions, float),
        np.asarray(lengths, float),
        sensor,
        config,
    )
    return posed, out, confusability(posed, out, sensor, config)


# ---------------------------------------------------------------- slow reference


def _seg_dist(p, a, b):
    ab = b - a
    u = min(1.0, max(0.0, float((p - a) @ ab) / max(float(ab @ ab), 1e-300)))
    return float(math.hypot(*(p - a - u * ab)))


def _cone(a, b):
    ang_a = math.atan2(a[1], a[0])
    diff = float(wrap_angle(math.atan2(b[1], b[0]) - ang_a))
    return float(wrap_angle(ang_a + diff / 2)), abs(diff) / 2


def _within(o, d, length, a, b, r, start=0.0, steps=80):
    """The stretch [lo, hi] of s in [start, length] where o + s d lies within r of
    the segment [a, b], or None: the distance is convex in s, so its least point is
    found by ternary search and the ends by bisection on each side."""

    def gap(t):
        return _seg_dist(o + t * d, a, b)

    lo, hi = float(start), float(length)
    for _ in range(steps):
        m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        lo, hi = (lo, m2) if gap(m1) <= gap(m2) else (m1, hi)
    best = (lo + hi) / 2
    if gap(best) > r:
        return None

    def edge(inside, outside):
        if gap(outside) <= r:
            return outside
        for _ in range(steps):
            mid = (inside + outside) / 2
            inside, outside = (mid, outside) if gap(mid) <= r else (inside, mid)
        return inside

    return edge(best, float(start)), edge(best, float(length))


def _near_slot(o, d, length, s, e, n, faces, r, start=0.0):
    """The slot of every stretch of the path from `start` on within `r` of one of
    `faces`, as one stretch with the cone of their normals (None if there is none)."""
    spans = [(g, _within(o, d, length, s[g], e[g], r, start)) for g in faces]
    spans = [(g, span) for g, span in spans if span is not None]
    if not spans:
        return None
    lo, hi = min(span[0] for _, span in spans), max(span[1] for _, span in spans)
    base = math.atan2(n[spans[0][0]][1], n[spans[0][0]][0])
    turns = [
        (math.atan2(n[g][1], n[g][0]) - base + math.pi) % (2 * math.pi) - math.pi for g, _ in spans
    ]
    centre = base + (min(turns) + max(turns)) / 2
    spread = min((max(turns) - min(turns)) / 2, math.pi)
    return (True, True, o + (lo + hi) / 2 * d, centre, spread, (hi - lo) / 2)


def reference_outcome(posed, h, o, d, length, sensor, config):
    """One path against one hypothesis with loops: (nominal, flags, slots)."""
    faces = [f for f in range(posed.valid.shape[1]) if posed.valid[h, f]]
    s, e, n = posed.start[h], posed.end[h], posed.normal[h]
    geometric = posed.eps_t[h] / 2 + config.contact_patch + 1e-9 * posed.scale
    vertex_tol = geometric + sensor.position_error
    graze = math.sin(min(config.grazing_angle + posed.rotation[h], math.pi / 2))
    turn_sin = math.sin(min(posed.rotation[h], math.pi / 2))

    def hits(excluded=(), front_only=False, after=None):
        """The first face met (t, f), or the first crossing strictly beyond `after`."""
        best = (math.inf, -1)
        for f in faces:
            if f in excluded or (front_only and d @ n[f] >= 0):
                continue
            edge = e[f] - s[f]
            denom = d[0] * edge[1] - d[1] * edge[0]
            if abs(denom) <= 1e-12 * posed.length[h, f]:
                continue
            w = s[f] - o
            t = (w[0] * edge[1] - w[1] * edge[0]) / denom
            u = (w[0] * d[1] - w[1] * d[0]) / denom
            beyond = t >= 0 if after is None else t > after
            if beyond and t <= length and 0 <= u <= 1 and t < best[0]:
                best = (t, f)
        return best

    t, f = hits()
    hit = f >= 0
    flags = dict(
        vertex=False,
        grazing=False,
        near_miss=False,
        end_of_path=False,
        shallow=False,
        close_pass=False,
        stretch=False,
        open_stretch=False,
    )
    slots = [(True, hit, o + t * d if hit else None, 0.0, 0.0, 0.0)]
    if hit:
        p, normal = o + t * d, n[f]
        cos_in = abs(float(d @ normal))
        to_start = float(math.hypot(*(p - s[f])))
        to_end = float(math.hypot(*(p - e[f])))
        adjacent = posed.prev[h, f] if to_start <= to_end else posed.next[h, f]
        flags["vertex"] = min(to_start, to_end) <= vertex_tol
        flags["grazing"] = cos_in < graze
        along = geometric / max(cos_in, graze)
        flags["end_of_path"] = t > length - along
        # shallow: the deepest point of the chord to the next crossing
        t_exit, f_exit = hits(after=t + 1e-9 * posed.scale)
        chord = (t_exit if f_exit >= 0 else length) - t
        depth = chord / 2
        if f_exit >= 0:
            a, b = cos_in, abs(float(d @ n[f_exit]))
            corner = chord * a * b / max(a + b, 1e-12)
            depth = min(depth, corner)
        flags["shallow"] = depth < vertex_tol
        # close pass: a vertex outside the contact's zone within its zone of the way in
        passes = [(_seg_dist(s[k], o, p), k) for k in faces if math.hypot(*(s[k] - p)) > vertex_tol]
        gap, k = min(passes, default=(math.inf, -1))
        flags["close_pass"] = gap <= vertex_tol
        # stretch: past the hit, while the path lies within 2 geometric + eps_d of
        # the outline (points half a vertex zone apart, up to the exit, 16 steps on),
        # the other faces turned toward it within 1.25 vertex zones of a point
        step, reach = vertex_tol / 2, 1.25 * vertex_tol
        deep, end = reach, (t_exit if f_exit >= 0 else length)
        base, turns, first = math.atan2(normal[1], normal[0]), [0.0], 17
        for j in range(17):
            if j > 0 and t + j * step >= end:
                first = j
                break
            q = o + (t + j * step) * d
            gaps = {g: _seg_dist(q, s[g], e[g]) for g in faces}
            turns += [
                (math.atan2(n[g][1], n[g][0]) - base + math.pi) % (2 * math.pi) - math.pi
                for g, gap in gaps.items()
                if g != f and gap <= reach and float(d @ n[g]) < turn_sin
            ]
            if min(gaps.values()) > deep:
                first = j
                break
        stretch = min(first * step, max(end - t, 0.0))
        still_open = first > 16
        flags["stretch"] = still_open or min(turns) < 0 or max(turns) > 0
        flags["open_stretch"] = still_open
        slack = along - geometric
        away = float(d @ n[adjacent]) > -graze
        slip = (
            (flags["vertex"] and away)
            or flags["grazing"]
            or flags["end_of_path"]
            or flags["shallow"]
        )
        # slot 0: from the hit over the stretch, with the normals of the faces met
        # there; back to a close pass left without a slot
        crowded = flags["close_pass"] and flags["vertex"] and slip
        lo = min(float((s[k] - o) @ d), t) if crowded else t
        hi = t + (stretch if flags["stretch"] else 0.0)
        angle, spread = base, 0.0
        if flags["stretch"]:
            angle += (min(turns) + max(turns)) / 2
            spread = min((max(turns) - min(turns)) / 2, math.pi)
        if still_open or crowded:
            spread = math.pi
        slots[0] = (True, True, o + (lo + hi) / 2 * d, angle, spread, slack + (hi - lo) / 2)
        if flags["vertex"]:
            centre, spread = _cone(normal, n[adjacent])
            slots.append((True, True, p, centre, spread, slack))
        if flags["close_pass"] and (not flags["vertex"] or not slip):
            centre, spread = _cone(n[posed.prev[h, k]], n[k])
            slots.append((True, True, s[k], centre, spread, 0.0))
        if slip:
            near = [g for g in faces if _seg_dist(p, s[g], e[g]) <= vertex_tol]
            t2, f2 = hits(near, front_only=True)
            if flags["end_of_path"] or f2 < 0:
                slots.append((True, False, None, 0.0, 0.0, 0.0))
            else:
                slots.append((True, True, o + t2 * d, math.atan2(n[f2][1], n[f2][0]), 0.0, 0.0))
            # slipping on, the path may meet a face it passes near further on
            met = [g for g in faces if g not in near and float(d @ n[g]) < turn_sin]
            slot = _near_slot(o, d, length, s, e, n, met, vertex_tol, start=t)
            if slot is not None:
                slots.append(slot)
    else:
        # a miss: every stretch of the path within the vertex zone of a face it may
        # meet, found by bisection on the convex distance, as one stretch
        met = [g for g in faces if float(d @ n[g]) < turn_sin]
        slot = _near_slot(o, d, length, s, e, n, met, vertex_tol)
        if slot is not None:
            flags["near_miss"] = True
            slots.append(slot)
    return (hit, t, f), flags, slots


def reference_confusable(posed, slots_h, slots_g, h, g, sensor):
    if posed.cls[h] == posed.cls[g]:
        return True
    p_tol = 2 * sensor.position_error + (posed.eps_t[h] + posed.eps_t[g]) / 2
    p_tol += 1e-9 * posed.scale
    n_tol = 2 * sensor.normal_error + posed.rotation[h] + posed.rotation[g] + 1e-9
    for _, hit_a, p_a, ang_a, spr_a, sl_a in slots_h:
        for _, hit_b, p_b, ang_b, spr_b, sl_b in slots_g:
            if not hit_a and not hit_b:
                return True
            if hit_a and hit_b:
                gap = float(math.hypot(*(p_a - p_b)))
                turn = abs(float(wrap_angle(ang_a - ang_b)))
                if gap <= p_tol + sl_a + sl_b and turn <= n_tol + spr_a + spr_b:
                    return True
    return False


@st.composite
def scenes(draw):
    n = draw(st.integers(1, 4))
    coord = st.floats(-15, 15, allow_nan=False)
    hyps = [
        hyp(
            draw(st.sampled_from(sorted(SHAPES))),
            draw(coord),
            draw(coord),
            draw(st.floats(-math.pi, math.pi)),
            cls=i,
            eps_t=draw(st.floats(0, 4)),
            rotation=draw(st.floats(0, 0.05)),
        )
        for i in range(n)
    ]
    sensor = SensorBounds(draw(st.floats(0, 1)), draw(st.floats(0, 0.1)))
    seed = draw(st.integers(0, 2**31))
    return hyps, sensor, seed


def random_rays(posed, rng, count=12):
    angles = rng.uniform(-math.pi, math.pi, count)
    origins = WORKSPACE.radius * np.stack([np.cos(angles), np.sin(angles)], 1)
    aims = rng.uniform(-30, 30, (count, 2))
    # half the rays aim near a vertex, where the uncertain cases live
    vertices = posed.start[posed.valid]
    near = vertices[rng.integers(len(vertices), size=count // 2)]
    aims[: count // 2] = near + rng.normal(0, 1.0, near.shape)
    span = aims - origins
    dist = np.hypot(*span.T)
    directions, lengths = span / dist[:, None], dist * rng.uniform(0.6, 1.4, count)
    # two rays run nearly along a face: the grazing cases
    h, f = np.nonzero(posed.valid)
    for i in range(2):
        k = rng.integers(len(h))
        s, e, n = posed.start[h[k], f[k]], posed.end[h[k], f[k]], posed.normal[h[k], f[k]]
        turn = rng.uniform(0.01, 0.15) * rng.choice([-1, 1])
        edge = (e - s) / np.hypot(*(e - s))
        d = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]]) @ edge
        aim = (s + e) / 2 - 0.05 * n
        origins[-1 - i], directions[-1 - i], lengths[-1 - i] = aim - 80 * d, d, 85.0
    return origins, directions, lengths


@settings(max_examples=60, deadline=None)
@given(scenes())
def test_outcomes_match_slow_reference(scene):
    hyps, sensor, seed = scene
    config = OutcomeConfig()
    posed = pose_hypotheses(hyps, MODELS)
    origins, directions, lengths = random_rays(posed, np.random.default_rng(seed))
    out = predict_outcomes(posed, origins, directions, lengths, sensor, config)
    conf = confusability(posed, out, sensor, config)
    for name in (
        "vertex",
        "grazing",
        "near_miss",
        "end_of_path",
        "shallow",
        "close_pass",
        "stretch",
    ):
        if getattr(out, name).any():
            event(name)
    for c in range(len(origins)):
        refs = []
        for h in range(len(hyps)):
            (hit, t, f), flags, slots = reference_outcome(
                posed, h, origins[c], directions[c], lengths[c], sensor, config
            )
            refs.append(slots)
            assert out.hit[c, h] == hit
            for name, value in flags.items():
                assert getattr(out, name)[c, h] == value, name
            if hit:
                assert out.distance[c, h] == pytest.approx(t, abs=1e-9)
                assert out.face[c, h] == f
            # the first hit agrees with shapely's intersection of path and boundary
            outline, holes = posed.rings[h]
            line = shapely.LineString([origins[c], origins[c] + lengths[c] * directions[c]])
            touched = line.intersection(shapely.Polygon(outline, list(holes)).boundary)
            assert touched.is_empty == (not hit)
            if hit:
                first = shapely.distance(shapely.Point(origins[c]), touched)
                assert first == pytest.approx(t, abs=1e-7)
            assert out.slot_valid[c, h].sum() == len(slots)
        for h in range(len(hyps)):
            for g in range(len(hyps)):
                expected = reference_confusable(posed, refs[h], refs[g], h, g, sensor)
                assert conf[c, h, g] == expected, (c, h, g)


@st.composite
def class_scenes(draw):
    """Hypotheses sharing classes, some of them copies of others (exact ties)."""
    n = draw(st.integers(2, 7))
    coord = st.floats(-12, 12, allow_nan=False)
    hyps = []
    for _ in range(n):
        if hyps and draw(st.booleans()):
            # a copy of an earlier one, moved by nothing or a hair, in another class
            base = hyps[draw(st.integers(0, len(hyps) - 1))]
            dx, dt = draw(st.sampled_from([(0.0, 0.0), (1e-9, 0.0), (0.0, 1e-7), (0.0, 1e-5)]))
            hyps.append(
                dataclasses.replace(
                    base,
                    pose=Pose(base.pose.x + dx, base.pose.y, base.pose.theta + dt),
                    equivalence_class=draw(st.integers(0, 3)),
                )
            )
            continue
        hyps.append(
            hyp(
                draw(st.sampled_from(sorted(SHAPES))),
                draw(coord),
                draw(coord),
                draw(st.floats(-math.pi, math.pi)),
                cls=draw(st.integers(0, 3)),
                eps_t=draw(st.sampled_from([0.0, 1.0, 3.0])),
                rotation=draw(st.sampled_from([0.0, 0.02])),
            )
        )
    sensor = draw(st.sampled_from([SensorBounds(0.0, 0.0), SensorBounds(1.0, math.radians(3))]))
    return hyps, sensor, draw(st.integers(0, 2**31))


def dense_confusability(posed, out, sensor):
    """Every outcome slot of h against every slot of g, pair by pair (`slots_match`)."""
    slots = Slots.of(posed, out, sensor)
    columns = [getattr(slots, f.name) for f in dataclasses.fields(Slots)]
    mine = Slots(*(col[:, :, None, :, None] for col in columns))
    theirs = Slots(*(col[:, None, :, None, :] for col in columns))
    return slots_match(mine, theirs).any(axis=(-1, -2)) | (posed.cls[:, None] == posed.cls[None, :])


@settings(max_examples=60, deadline=None)
@given(class_scenes())
def test_ties_and_classes_agree_with_the_pairwise_test(scene):
    # copies in other classes put outcomes exactly on (or a hair off) the tolerance
    # edges, where the interval passes hand over to the one-by-one test
    hyps, sensor, seed = scene
    posed = pose_hypotheses(hyps, MODELS)
    origins, directions, lengths = random_rays(posed, np.random.default_rng(seed), count=16)
    out = predict_outcomes(posed, origins, directions, lengths, sensor)
    conf = confusability(posed, out, sensor)
    np.testing.assert_array_equal(conf, dense_confusability(posed, out, sensor))
    # the class survivors straight from the outcomes: the class matrix of conf
    np.testing.assert_array_equal(
        class_survivors(posed, out, sensor).bits, survivor_table(posed, conf).bits
    )


@st.composite
def slot_scenes(draw):
    """Made-up outcome slots on a few paths: points on the path (near misses' closest
    approach off it, slot 1 only) at coarse distances and angles (many exact ties and
    touching tolerances), vertex cones up to most of a half turn, some reaching
    across the path's heading."""
    n_hyp, n_paths = draw(st.integers(2, 40)), draw(st.integers(1, 4))
    rng = np.random.default_rng(draw(st.integers(0, 2**31)))
    hyps = [
        hyp(
            "square",
            0.0,
            0.0,
            cls=int(rng.integers(0, max(1, n_hyp // 2))),
            eps_t=float(rng.choice([0.0, 1.0, 2.0])),
            rotation=float(rng.choice([0.0, 0.05, 0.25])),
        )
        for _ in range(n_hyp)
    ]
    sensor = SensorBounds(float(rng.choice([0.0, 0.5])), float(rng.choice([0.0, 0.05])))
    shape = (n_paths, n_hyp, SLOTS)
    heading = rng.uniform(-math.pi, math.pi, n_paths)
    valid = rng.random(shape) < 0.8
    valid[..., 0] = True
    hit = valid & (rng.random(shape) < 0.85)
    distance = np.where(hit, rng.integers(0, 12, shape) / 2.0, np.nan)
    offset = np.zeros(shape)
    offset[..., 1] = np.where(rng.random(shape[:2]) < 0.3, rng.integers(-4, 5, shape[:2]) / 4, 0)
    offset = np.where(hit, offset, 0.0)
    # normals facing back along the path, or anywhere
    back = heading[:, None, None] + math.pi + rng.integers(-6, 7, shape) * math.pi / 12
    angle = np.where(rng.random(shape) < 0.8, back, rng.integers(-12, 12, shape) * math.pi / 12)
    spread = np.where(rng.random(shape) < 0.3, rng.integers(0, 11, shape) * math.pi / 24, 0.0)
    slack = np.where(rng.random(shape) < 0.2, rng.integers(0, 3, shape) / 2, 0.0)
    d = np.stack([np.cos(heading), np.sin(heading)], axis=-1)[:, None, None, :]
    left = np.stack([-d[..., 1], d[..., 0]], axis=-1)
    origin = rng.uniform(-5, 5, (n_paths, 1, 1, 2))
    point = origin + distance[..., None] * d + offset[..., None] * left
    return hyps, sensor, heading, valid, hit, point, angle, spread, slack, distance, offset


@settings(max_examples=120, deadline=None)
@given(slot_scenes(), st.booleans())
def test_interval_passes_agree_with_the_pairwise_test(scene, every_path):
    # hit slots are tested pair by pair along each path, or (with many pairs in
    # reach of each other) by sorted interval ends; `every_path` sends all that way
    hyps, sensor, heading, valid, hit, point, angle, spread, slack, distance, offset = scene
    posed = pose_hypotheses(hyps, MODELS)
    nominal = point[:, :, 0]
    out = Outcomes(
        hit=hit[..., 0],
        distance=np.where(hit[..., 0], distance[..., 0], np.inf),
        point=nominal,
        normal=np.stack([np.cos(angle[..., 0]), np.sin(angle[..., 0])], axis=-1),
        face=np.where(hit[..., 0], 0, -1),
        travel=np.zeros(hit.shape[:2]),
        vertex=valid[..., 1] & hit[..., 1],
        grazing=np.zeros(hit.shape[:2], dtype=bool),
        near_miss=np.zeros(hit.shape[:2], dtype=bool),
        end_of_path=np.zeros(hit.shape[:2], dtype=bool),
        shallow=np.zeros(hit.shape[:2], dtype=bool),
        close_pass=np.zeros(hit.shape[:2], dtype=bool),
        stretch=np.zeros(hit.shape[:2], dtype=bool),
        open_stretch=np.zeros(hit.shape[:2], dtype=bool),
        slot_valid=valid,
        slot_hit=hit,
        slot_point=point,
        slot_angle=angle,
        slot_spread=spread,
        slot_slack=slack,
        slot_distance=distance,
        slot_offset=offset,
        heading=heading,
    )
    slots = Slots.of(posed, out, sensor)
    u = np.mod(angle - heading[:, None, None], 2 * math.pi)
    if (hit & ((u - slots.alpha < 0) | (u + slots.alpha > 2 * math.pi))).any():
        event("an arc across the heading")
    with pytest.MonkeyPatch.context() as patch:
        if every_path:
            patch.setattr(matching, "_PAIRS_PER_HIT", 0)
        conf = confusability(posed, out, sensor)
        table = class_survivors(posed, out, sensor)
    np.testing.assert_array_equal(conf, dense_confusability(posed, out, sensor))
    np.testing.assert_array_equal(table.bits, survivor_table(posed, conf).bits)


def test_chunking_does_not_change_outcomes():
    rng = np.random.default_rng(3)
    hyps = [hyp("ell", *rng.uniform(-10, 10, 2), rng.uniform(-3, 3), cls=i) for i in range(6)]
    posed = pose_hypotheses(hyps, MODELS)
    rays = random_rays(posed, rng, count=40)
    sensor = SensorBounds(0.5, 0.05)
    whole = predict_outcomes(posed, *rays, sensor)
    tiny = OutcomeConfig(chunk_elements=50)
    parts = predict_outcomes(posed, *rays, sensor, tiny)
    for name in ("hit", "face", "vertex", "near_miss", "slot_valid", "slot_hit"):
        np.testing.assert_array_equal(getattr(whole, name), getattr(parts, name))
    np.testing.assert_array_equal(
        confusability(posed, whole, sensor), confusability(posed, parts, sensor, tiny)
    )


DOWN = ([[0.0, 100.0]], [[0.0, -1.0]], [100.0])


@pytest.mark.parametrize(
    ("shift", "expected"),
    [(2.9, True), (3.1, False)],  # tolerance 2 eps_d + (eps_t + eps_t) / 2 = 1 + 2 = 3
)
def test_point_tolerance(shift, expected):
    hyps = [hyp("square", 0, 0, cls=0, eps_t=2.0), hyp("square", 0, shift, cls=1, eps_t=2.0)]
    # (the path meets both top faces head on, far from any vertex)
    _, out, conf = cast(hyps, *DOWN, sensor=SensorBounds(0.5, 0.0))
    assert not out.uncertain.any()
    assert conf[0, 0, 1] == expected == conf[0, 1, 0]


@pytest.mark.parametrize(("turn", "expected"), [(0.049, True), (0.051, False)])
def test_normal_tolerance(turn, expected):
    # tolerance 2 phi + dtheta(h) + dtheta(g) = 0.02 + 0.015 + 0.015 = 0.05 radians
    hyps = [
        hyp("square", 0, 0, cls=0, eps_t=1.0, rotation=0.015),
        hyp("square", 0, 0, turn, cls=1, eps_t=1.0, rotation=0.015),
    ]
    _, out, conf = cast(hyps, *DOWN, sensor=SensorBounds(0.0, 0.01))
    assert out.hit.all() and not out.uncertain.any()
    assert abs(out.point[0, 0, 1] - out.point[0, 1, 1]) < 2  # same place, other normal
    assert conf[0, 0, 1] == expected


@pytest.mark.parametrize(("eps_t", "vertex"), [(2.0, True), (0.0, False)])
def test_vertex_hit_is_confusable_with_a_normal_of_the_corner(eps_t, vertex):
    # h's path hits its top face 0.5 from the corner (20, 20), whose normals span
    # +x..+y; g (a diamond) shows a face with normal at 45 degrees 0.7 away
    h = hyp("square", 0, 0, cls=0, eps_t=eps_t)
    g = hyp("square", 20 - 20 * math.sqrt(2), 20, math.pi / 4, cls=1)
    sensor = SensorBounds(0.3, 0.0)
    _, out, conf = cast([h, g], [[19.5, 100.0]], [[0.0, -1.0]], [100.0], sensor)
    assert out.vertex[0, 0] == vertex  # zone: eps_t / 2 + eps_d
    assert not out.uncertain[0, 1]
    gap = np.hypot(*(out.point[0, 0] - out.point[0, 1]))
    assert gap <= 2 * 0.3 + eps_t / 2  # the points alone would match
    assert conf[0, 0, 1] == vertex  # only the corner's cone of normals makes the match


def test_grazing_hit_is_confusable_with_a_miss():
    # the path runs 0.02 rad off parallel to the top face and hits it
    h = hyp("square", 0, 0, cls=0)
    miss = hyp("square", 0, -60, cls=1)
    angle = 0.02
    d = [-math.cos(angle), -math.sin(angle)]
    o = [100.0, 20.0 + 100 * math.tan(angle)]  # meets the top face at (0, 20)
    _, out, conf = cast([h, miss], [o], [d], [150.0])
    assert out.hit[0, 0] and out.grazing[0, 0]
    assert not out.hit[0, 1]
    assert conf[0, 0, 1]
    # head on, a hit and a miss are told apart
    _, out2, conf2 = cast([h, miss], *DOWN)
    assert out2.hit[0, 0] and not out2.hit[0, 1] and not conf2[0, 0, 1]


def test_near_miss_is_confusable_with_a_hit_at_the_corner():
    # the path passes 0.5 from the corner (20, 20) of h; eps_t = 2 puts it in reach
    h = hyp("square", 0, 0, cls=0, eps_t=2.0)
    g = hyp("square", 3.0, 0, cls=1, eps_t=2.0)
    ray = ([[20.5, 100.0]], [[0.0, -1.0]], [100.0])
    _, out, conf = cast([h, g], *ray)
    assert out.near_miss[0, 0] and not out.hit[0, 0]
    assert out.hit[0, 1]
    assert conf[0, 0, 1]
    # further away it is a plain miss
    _, out2, _ = cast([h], [[25.0, 100.0]], [[0.0, -1.0]], [100.0])
    assert not out2.near_miss[0, 0] and not out2.uncertain[0, 0]


def test_a_grazing_corner_hit_may_come_at_the_corner_passed_before():
    # the path runs 0.5 below h's corner (-20, -20), then grazes its bottom face up to
    # the far corner: the true outline may be met at the first corner already
    h = hyp("square", 0, 0, cls=0, eps_t=2.0)
    g = hyp("square", 0, -0.8, cls=1, eps_t=2.0)  # met square on its left face there
    d = np.array([39.8, 0.5]) / math.hypot(39.8, 0.5)
    origin = np.array([-20.0, -20.5]) - 40.0 * d / d[0]
    _, out, conf = cast([h, g], [origin], [d], [100.0])
    assert out.vertex[0, 0] and out.grazing[0, 0] and out.close_pass[0, 0]
    assert out.point[0, 1, 0] == pytest.approx(-20.0)
    assert conf[0, 0, 1] and conf[0, 1, 0]


def test_contact_at_the_end_of_the_path_may_be_a_miss():
    h = hyp("square", 0, 0, cls=0, eps_t=2.0)
    miss = hyp("square", 0, -70, cls=1)
    _, out, conf = cast([h, miss], [[0.0, 100.0]], [[0.0, -1.0]], [80.5])
    assert out.hit[0, 0] and out.end_of_path[0, 0]
    assert conf[0, 0, 1]


def test_unbounded_error_is_confusable_with_everything():
    lost = Hypothesis("square", 0, (), Pose(0, 0, 0), ErrorBound(math.inf, math.nan, math.inf), 0.5)
    other = hyp("triangle", 30, 30, cls=1, p=0.5)
    rays = ([[100.0, 0.0], [0.0, 100.0], [-100.0, 90.0]], [[-1, 0], [0, -1], [1, 0]], [100] * 3)
    _, out, conf = cast([lost, other], *rays)
    assert np.isfinite(out.slot_slack).all()
    assert conf.all()


def test_equivalent_hypotheses_stay_together():
    # a square turned by 90 degrees has the same outline: one equivalence class
    hyps = [
        hyp("square", 0, 0, 0.0, cls=7, p=0.25),
        hyp("square", 0, 0, math.pi / 2, cls=7, p=0.25),
        hyp("square", 8, 0, 0.0, cls=9, p=0.5),
    ]
    posed, _, conf = cast(hyps, [[100.0, 0.0], [0.0, 100.0]], [[-1, 0], [0, -1]], [100, 100])
    table = survivor_table(posed, conf)
    assert table.n_classes == 2
    np.testing.assert_allclose(table.weight, [0.5, 0.5])
    assert conf[:, 0, 1].all()
    matrix = table.matrix()
    # from the right the classes differ, from above they coincide
    assert not matrix[0, 0, 1] and matrix[1, 0, 1]


def test_inseparable_classes_are_marked():
    hyps = [hyp("square", 0, 0, cls=0), hyp("square", 0, 0, math.pi / 2, cls=1)]
    posed, _, conf = cast(hyps, [[100.0, 0.0]], [[-1.0, 0.0]], [100.0])
    table = survivor_table(posed, conf)
    assert unpack_bits(table.inseparable, 2).all()


def test_survivor_table_matches_the_class_matrix():
    rng = np.random.default_rng(5)
    hyps = [
        hyp("triangle", *rng.uniform(-8, 8, 2), rng.uniform(-3, 3), cls=i % 4) for i in range(9)
    ]
    posed = pose_hypotheses(hyps, MODELS)
    rays = random_rays(posed, rng, count=20)
    conf = confusability(
        posed, predict_outcomes(posed, *rays, SensorBounds(0.3, 0.02)), SensorBounds(0.3, 0.02)
    )
    table = survivor_table(posed, conf)
    matrix = table.matrix()
    for a in range(4):
        for b in range(4):
            expected = conf[:, posed.cls == a][:, :, posed.cls == b].any(axis=(1, 2))
            np.testing.assert_array_equal(matrix[:, a, b], expected)


def test_bitsets_round_trip_over_several_words():
    rng = np.random.default_rng(1)
    mask = rng.random((5, 70, 70)) < 0.3
    words = pack_bits(mask)
    assert words.shape == (5, 70, 2) and words.dtype == np.uint64
    np.testing.assert_array_equal(unpack_bits(words, 70), mask)
    np.testing.assert_array_equal(popcount(words), mask.sum(-1))
    assert to_int(words[0, 0]) == sum(1 << int(j) for j in np.flatnonzero(mask[0, 0]))
    table = SurvivorTable.from_matrix(mask, np.ones(70))
    assert table.matrix()[:, np.arange(70), np.arange(70)].all()


@pytest.mark.parametrize("chunk", [1, 50, 1_000_000])
def test_contains_points_agrees_with_shapely_in_chunks_of_any_size(chunk, monkeypatch):
    # the point x hypothesis x face passes go in chunks: a round part's many faces
    # times thousands of hypotheses must not be held at once
    monkeypatch.setattr("planner.planning.posed_set.CHUNK_ELEMENTS", chunk)
    monkeypatch.setattr("planner.planning.intersection_aims.CHUNK_ELEMENTS", chunk)
    rng = np.random.default_rng(2)
    hyps = [hyp(name, *rng.uniform(-5, 5, 2), rng.uniform(-3, 3)) for name in sorted(SHAPES)]
    posed = pose_hypotheses(hyps, MODELS)
    points = rng.uniform(-40, 40, (300, 2))
    inside = contains_points(posed, points)
    xs, ys = np.linspace(-40, 40, 13), np.linspace(-30, 30, 7)
    grid = _grid_depth(posed, xs, ys)
    gx, gy = np.meshgrid(xs, ys)
    for h, (outline, holes) in enumerate(posed.rings):
        poly = shapely.Polygon(outline, list(holes))
        np.testing.assert_array_equal(inside[:, h], shapely.contains_xy(poly, *points.T))
        np.testing.assert_array_equal(grid[:, h], shapely.contains_xy(poly, gx.ravel(), gy.ravel()))


def _scene(n=8, seed=4):
    rng = np.random.default_rng(seed)
    return [
        hyp("ell", *rng.uniform(-2, 2, 2), rng.uniform(-0.05, 0.05), cls=i, p=1 / n, eps_t=1.0)
        for i in range(n)
    ]


def test_candidates_start_on_the_safe_circle():
    posed = pose_hypotheses(_scene(), MODELS)
    config = CandidateConfig(count=60)
    extra = Candidates.from_paths([SensingPath((100.0, 0.0), (-1.0, 0.0), 150.0)] * 2)
    c = generate_candidates(
        posed, WORKSPACE, SensorBounds(0.5, 0.05), config, np.random.default_rng(0), extra=extra
    )
    assert len(c) == 2 + 60
    assert list(c.source[:2]) == ["extra", "extra"]  # kept whole, first
    np.testing.assert_allclose(np.hypot(*c.origins.T), WORKSPACE.radius)
    np.testing.assert_allclose(np.hypot(*c.directions.T), 1.0)
    # the general ones are deduped by direction (1 degree) and line offset (R / 200)
    general = c.subset(np.arange(2, len(c)))
    angle = np.round(
        np.arctan2(general.directions[:, 1], general.directions[:, 0]) / config.angle_step
    )
    offset = (
        general.directions[:, 0] * general.origins[:, 1]
        - general.directions[:, 1] * general.origins[:, 0]
    )
    keys = set(zip(angle.astype(int) % 360, np.round(offset / 0.5).astype(int), strict=True))
    assert len(keys) == len(general)
    # intersection-area paths end inside every posed outline
    ia = general.source == "intersection"
    assert ia.any() and (general.source == "boundary").any()
    assert contains_points(posed, general.aims[ia]).all()


def test_candidate_count_is_configurable():
    posed = pose_hypotheses(_scene(), MODELS)
    sizes = [
        len(generate_candidates(posed, WORKSPACE, SensorBounds(), CandidateConfig(count=n)))
        for n in (0, 10, 40)
    ]
    assert sizes == [0, 10, 40]


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 3), st.integers(1, 140), st.integers(1, 140), st.integers(0, 2**31))
def test_transpose_bits_and_weighted_count(lead, rows, cols, seed):
    rng = np.random.default_rng(seed)
    mask = rng.random((lead, rows, cols)) < 0.4
    words = pack_bits(mask)
    np.testing.assert_array_equal(
        unpack_bits(transpose_bits(words, cols), rows), mask.swapaxes(1, 2)
    )
    np.testing.assert_array_equal(popcount(words), mask.sum(-1))
    weight = rng.random(cols)
    np.testing.assert_allclose(weighted_count(words, weight), mask @ weight, rtol=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    st.integers(1, 5), st.integers(1, 70), st.integers(0, 2**31), st.sampled_from(["left", "right"])
)
def test_sorted_count_is_searchsorted_on_each_row(n_rows, n, seed, side):
    rng = np.random.default_rng(seed)
    # coarse values (many ties) and +inf padding, as the interval lists hold
    ends = np.sort(rng.integers(0, 12, (n_rows, n)) / 2, axis=1)
    ends[:, n - int(rng.integers(0, n + 1)) :] = np.inf
    rows = rng.integers(0, n_rows, 40)
    x = rng.integers(-1, 14, 40) / 2
    want = [np.searchsorted(ends[r], v, side=side) for r, v in zip(rows, x, strict=True)]
    assert sorted_count(ends, rows, x, side).tolist() == want


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 4), st.integers(1, 30), st.integers(0, 2**31))
def test_interval_unions_agree_with_brute_force(n_rows, n, seed):
    rng = np.random.default_rng(seed)
    # coarse values: many exact ties between ends
    centre, half = rng.integers(0, 20, (n_rows, n)) / 2, rng.integers(0, 4, (n_rows, n)) / 2
    low, high = centre - half, centre + half
    member = rng.random((n_rows, n)) < 0.7
    owner = np.broadcast_to(np.arange(n), (n_rows, n))
    unions = IntervalUnions.of(low, high, owner, member, 1)
    rows = rng.integers(0, n_rows, 25)
    q_lo = rng.integers(0, 20, 25) / 2
    q_hi = q_lo + rng.integers(0, 4, 25) / 2
    got = unpack_bits(unions.overlapping(rows, q_lo, q_hi), n)
    expected = member[rows] & (low[rows] <= q_hi[:, None]) & (high[rows] >= q_lo[:, None])
    np.testing.assert_array_equal(got, expected)
    # an interval's R end within [R - 0.5, R + 0.5] of another member's L end
    near = close_ends(low, high, member, -0.5, 0.5)
    gap = low[:, None, :] - high[:, :, None]
    want = ((gap >= -0.5) & (gap <= 0.5) & member[:, None, :]).any(axis=2) & member
    np.testing.assert_array_equal(near, want)
