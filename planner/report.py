"""A session's report: every touch with its residuals against the answer, and the answer
(object, stable pose, pose with its bound, probability, status), as JSON-ready data and
as CSV (DESIGN §6).

Residuals are taken against the most probable hypothesis, in the object files' unit and
radians: for a contact, `distance` from the contact point to the posed face it is
assigned to and `normal_angle`, the signed angle from that face's outward normal to the
measured one (counter-clockwise positive); a contact the hypothesis calls spurious has
none; for a miss, `clearance` is how far the path passed from the posed outline (holes
included: the object's material).

>>> from planner.models.outlines import make_stable_pose
>>> from planner.recognition.session import Session
>>> from planner.types import Contact, ObjectModel, Observation, SensingPath, Workspace
>>> sq = ObjectModel("square", (make_stable_pose([[-20, -20], [20, -20], [20, 20], [-20, 20]]),))
>>> s = Session([sq], workspace=Workspace((0.0, 0.0), 100.0)).observe(
...     Observation(SensingPath((0, -100), (0, 1), 200), Contact((3, -20), (0, -1))))
>>> touch = session_report(s)["touches"][0]
>>> touch["kind"], touch["face"], round(touch["distance"], 9)
('contact', 0, 0.0)
"""

from __future__ import annotations

import csv
import io
import math
from typing import Any

import numpy as np
import shapely

from planner.geometry import wrap_angle
from planner.recognition.session import Session
from planner.types import Hypothesis, Observation

__all__ = ["CSV_COLUMNS", "report_csv", "session_report"]

#: The CSV's columns: one row per touch (`kind` contact, spurious or miss), then one
#: `result` row with the answer (empty cells where a column does not apply).
CSV_COLUMNS = (
    "row",
    "kind",
    "index",
    "origin_x",
    "origin_y",
    "direction_x",
    "direction_y",
    "length",
    "point_x",
    "point_y",
    "normal_x",
    "normal_y",
    "face",
    "distance",
    "normal_angle",
    "clearance",
    "status",
    "object",
    "stable_pose",
    "x",
    "y",
    "theta",
    "translation_bound",
    "rotation_bound",
    "eps_t",
    "probability",
    "class_probability",
    "height",
)


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _residuals(session: Session, best: Hypothesis | None) -> list[dict[str, Any]]:
    touches: list[dict[str, Any]] = []
    stable = faces = None
    if best is not None:
        stable = session.models_by_name[best.object].stable_poses[best.stable_pose]
        faces = stable.all_faces  # assignments index every layer's faces
    contact_no = 0
    for i, obs in enumerate(session.observations):
        row: dict[str, Any] = {
            "index": i,
            "path": {
                "origin": [float(v) for v in obs.path.origin],
                "direction": [float(v) for v in obs.path.direction],
                "length": float(obs.path.length),
                "height": obs.path.height,
            },
            "contact": None,
            "face": None,
            "distance": None,
            "normal_angle": None,
            "clearance": None,
        }
        if obs.contact is None:
            row["kind"] = "miss"
            if best is not None and stable is not None:
                layer = stable.layer(obs.path.height)  # the outline at the path's height
                rings = [best.pose.apply(r) for r in (layer.outline, *layer.holes)]
                row["clearance"] = _clearance(obs, shapely.Polygon(rings[0], rings[1:]))
        else:
            c = obs.contact
            row["contact"] = {
                "point": [float(v) for v in c.point],
                "normal": [float(v) for v in c.normal],
            }
            face = None if best is None else best.assignment[contact_no]
            contact_no += 1
            row["kind"] = "contact" if face is not None or best is None else "spurious"
            if face is not None and faces is not None and best is not None:
                row["face"] = int(face)
                row["distance"], row["normal_angle"] = _contact_residual(best, faces, face, c)
        touches.append(row)
    return touches


def _contact_residual(best: Hypothesis, faces: Any, face: int, contact: Any) -> tuple[float, float]:
    # the face posed in the world: a = R s + t, b = R e + t, n_w = R n
    a, b = best.pose.apply(np.stack([faces.start[face], faces.end[face]]))
    n_w = best.pose.rotation() @ faces.normal[face]
    p = np.asarray(contact.point, dtype=float)
    ab = b - a
    s = float(np.clip((p - a) @ ab / max(float(ab @ ab), 1e-300), 0.0, 1.0))
    distance = float(np.hypot(*(p - (a + s * ab))))
    measured = math.atan2(contact.normal[1], contact.normal[0])
    angle = float(wrap_angle(measured - math.atan2(n_w[1], n_w[0])))
    return distance, angle


def _clearance(obs: Observation, material: shapely.Polygon) -> float | None:
    o = np.asarray(obs.path.origin, dtype=float)
    end = o + obs.path.length * np.asarray(obs.path.direction, dtype=float)
    return _finite(shapely.distance(shapely.LineString([o, end]), material))


def session_report(session: Session) -> dict[str, Any]:
    """The report of `session`: `status`, `objects`, `sensor` bounds, `touches` (one
    entry per observation, in order, with residuals against the most probable
    hypothesis) and `result` (that hypothesis with its class' probability and the
    class bound `localized` is judged on; None without a hypothesis)."""
    hyps = session.hypotheses
    best = hyps[0] if hyps else None
    result = None
    if best is not None:
        loc = session.localization
        bound = loc.bound or best.error_bound
        result = {
            "object": best.object,
            "stable_pose": int(best.stable_pose),
            "pose": {
                "x": float(best.pose.x),
                "y": float(best.pose.y),
                "theta": float(best.pose.theta),
            },
            "bound": {
                "translation": _finite(bound.translation),
                "rotation": _finite(bound.rotation),
                "eps_t": _finite(bound.eps_t),
            },
            "probability": min(max(float(best.probability), 0.0), 1.0),
            "class_probability": min(
                1.0,
                sum(
                    float(h.probability)
                    for h in hyps
                    if h.equivalence_class == best.equivalence_class
                ),
            ),
            "classes": int(loc.classes),
            "missing": list(loc.missing),
        }
    return {
        "status": session.status,
        "objects": [m.name for m in session.models],
        "sensor": {
            "position_error": float(session.sensor.position_error),
            "normal_error": float(session.sensor.normal_error),
        },
        "accuracy": {
            "translation": float(session.accuracy.translation),
            "rotation": float(session.accuracy.rotation),
        },
        "touches": _residuals(session, best),
        "result": result,
    }


def report_csv(report: dict[str, Any]) -> str:
    """The report as CSV (:data:`CSV_COLUMNS`, header first; readable with the standard
    library's ``csv.DictReader``): a row per touch, then the `result` row."""
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=CSV_COLUMNS, lineterminator="\n")
    writer.writeheader()
    for t in report["touches"]:
        c = t["contact"] or {"point": [None, None], "normal": [None, None]}
        writer.writerow(
            _cells(
                row="touch",
                kind=t["kind"],
                index=t["index"],
                origin_x=t["path"]["origin"][0],
                origin_y=t["path"]["origin"][1],
                direction_x=t["path"]["direction"][0],
                direction_y=t["path"]["direction"][1],
                length=t["path"]["length"],
                point_x=c["point"][0],
                point_y=c["point"][1],
                normal_x=c["normal"][0],
                normal_y=c["normal"][1],
                face=t["face"],
                distance=t["distance"],
                normal_angle=t["normal_angle"],
                clearance=t["clearance"],
                height=t["path"].get("height"),
            )
        )
    r = report["result"]
    final = {"row": "result", "status": report["status"]}
    if r is not None:
        final |= {
            "object": r["object"],
            "stable_pose": r["stable_pose"],
            "x": r["pose"]["x"],
            "y": r["pose"]["y"],
            "theta": r["pose"]["theta"],
            "translation_bound": r["bound"]["translation"],
            "rotation_bound": r["bound"]["rotation"],
            "eps_t": r["bound"]["eps_t"],
            "probability": r["probability"],
            "class_probability": r["class_probability"],
        }
    writer.writerow(_cells(**final))
    return out.getvalue()


def _cells(**values: Any) -> dict[str, str]:
    # repr of floats round-trips exactly; None is an empty cell
    return {
        k: "" if v is None else repr(v) if isinstance(v, float) else str(v)
        for k, v in values.items()
    }
