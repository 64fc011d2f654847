"""The live session viewer: the MII as JSON geometry, and a self-contained HTML page
that draws it as SVG in the browser and refreshes while the session changes."""

from __future__ import annotations

import base64
import hashlib
from typing import Any

import shapely

from planner.codec import contact_to_dict, path_to_dict, workspace_to_dict
from planner.recognition.session import Session

__all__ = ["VIEW_CSP", "VIEW_HTML", "mii_json"]


def _rings(geom: shapely.Geometry) -> list[list[list[list[float]]]]:
    """Polygons of a geometry as [exterior, *holes] coordinate lists."""
    polys = [
        g for g in shapely.get_parts(geom) if isinstance(g, shapely.Polygon) and not g.is_empty
    ]
    return [
        [[list(map(float, c)) for c in ring.coords] for ring in [p.exterior, *p.interiors]]
        for p in polys
    ]


def _lines(geom: shapely.Geometry) -> list[list[list[float]]]:
    parts = [g for g in shapely.get_parts(geom) if isinstance(g, shapely.LineString)]
    return [[list(map(float, c)) for c in g.coords] for g in parts if not g.is_empty]


def mii_json(session: Session, sensor_position: list[float]) -> dict[str, Any]:
    """World-frame geometry of the session's MII for drawing (lengths in model units):
    of many hypotheses the most probable within the drawing budget
    (:func:`~planner.image.vector.drawable`), `drawn` of `hypothesis_count`."""
    from planner.image.vector import build_mii, drawable

    hyps = drawable(session.hypotheses, session.models)
    out: dict[str, Any] = {
        "hypothesis_count": len(session.hypotheses),
        "drawn": len(hyps),
        "status": session.status,
        "workspace": workspace_to_dict(session.workspace),
        "sensor_position": list(sensor_position),
        "outlines": [],
        "intersection": [],
        "blocking": [],
        "observations": [
            {**path_to_dict(o.path), "contact": contact_to_dict(o.contact, normal_z="omit")}
            for o in session.observations
        ],
    }
    if not hyps:
        return out
    mii = build_mii(hyps, session.models)
    for h, polygon in zip(mii.hypotheses, mii.outlines, strict=True):
        out["outlines"].append(
            {
                "object": h.object,
                "stable_pose": h.stable_pose,
                "probability": h.probability,
                "equivalence_class": h.equivalence_class,
                "rings": _rings(polygon)[0] if not polygon.is_empty else [],
            }
        )
    out["intersection"] = _rings(mii.intersection)
    for b in mii.blocking:
        out["blocking"].append(
            {
                "strength": float(b.strength),
                "degree": int(b.degree),
                "polygons": _rings(b.geometry) if b.is_region else [],
                "lines": [] if b.is_region else _lines(b.geometry),
            }
        )
    return out


VIEW_HTML = """<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<title>tactile-planner session</title>
<style>
 body{font-family:system-ui,sans-serif;margin:1rem;color:#222;background:#fafafa}
 #wrap{display:flex;gap:1.5rem;flex-wrap:wrap}
 svg{background:#fff;border:1px solid #ccc}
 table{border-collapse:collapse;font-size:.85rem}
 td,th{border-bottom:1px solid #ddd;padding:.2rem .5rem;text-align:right}
 th{background:#eee} td.l,th.l{text-align:left}
 #status{font-weight:bold} .muted{color:#777}
</style></head>
<body>
<h1>Session <span id="sid"></span></h1>
<p>Status: <span id="status">loading</span>, version <span id="version">-</span>,
 <span id="count">0</span> hypotheses. <span class="muted" id="note"></span></p>
<div id="wrap">
 <svg id="mii" width="640" height="640" role="img" aria-label="multi-interpretation image"></svg>
 <div>
  <h2>Planned paths</h2>
  <table id="paths"><thead><tr><th>#</th><th class="l">family</th><th>P(DM)</th>
   <th>P(inf)</th><th>E[touches]</th><th>motion</th></tr></thead><tbody></tbody></table>
  <h2>Hypotheses</h2>
  <table id="hypotheses"><thead><tr><th class="l">object</th><th>pose</th><th>x</th><th>y</th>
   <th>theta (deg)</th><th>eps_t</th><th>P</th><th>class</th></tr></thead><tbody></tbody></table>
 </div>
</div>
<script>
"use strict";
const base = location.pathname.replace(/\\/view$/, "");
// with an API key the page is opened through a viewer link; its reads carry the token
const token = new URLSearchParams(location.search).get("token");
const auth = token ? {headers: {Authorization: "Bearer " + token}} : {};
document.getElementById("sid").textContent = base.split("/").pop();
const NS = "http://www.w3.org/2000/svg";
const PALETTE = ["#1f77b4","#ff7f0e","#2ca02c","#d62728","#9467bd","#8c564b","#e377c2","#17becf"];
let shown = null;
function el(name, attrs, parent) {
  const e = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}
function ringPath(rings, flip) {
  return rings.map(r => "M" + r.map(p => p[0] + "," + (-p[1])).join("L") + "Z").join("");
}
function red(s) { const a = Math.max(0, Math.min(1, s)); return `rgba(200,20,20,${0.15 + 0.85 * a})`; }
function draw(img, plan) {
  const svg = document.getElementById("mii");
  while (svg.firstChild) svg.removeChild(svg.firstChild);
  const c = img.workspace.center, R = img.workspace.radius, m = 0.08 * R;
  svg.setAttribute("viewBox", [c[0]-R-m, -(c[1]+R+m), 2*(R+m), 2*(R+m)].join(" "));
  const w = R / 150;
  el("circle", {cx: c[0], cy: -c[1], r: R, fill: "none", stroke: "#888",
     "stroke-dasharray": 4*w, "stroke-width": w, id: "safe-circle"}, svg);
  const names = [...new Set(img.outlines.map(o => o.object))];
  const g = el("g", {id: "outlines"}, svg);
  img.outlines.forEach((o, i) => el("path", {d: ringPath(o.rings), class: "outline",
     fill: "none", stroke: PALETTE[names.indexOf(o.object) % PALETTE.length],
     "stroke-opacity": 0.25 + 0.75 * Math.min(1, o.probability * img.outlines.length),
     "stroke-width": 1.5*w}, g));
  const ia = el("g", {id: "intersection"}, svg);
  img.intersection.forEach(p => el("path", {d: ringPath(p), class: "ia", fill: "#2ca02c",
     "fill-opacity": 0.3, stroke: "none", "fill-rule": "evenodd"}, ia));
  const bl = el("g", {id: "blocking"}, svg);
  img.blocking.forEach(b => {
    b.polygons.forEach(p => el("path", {d: ringPath(p), class: "blocking", fill: red(b.strength),
       stroke: "none"}, bl));
    b.lines.forEach(l => el("path", {d: "M" + l.map(p => p[0] + "," + (-p[1])).join("L"),
       class: "blocking", stroke: red(b.strength), "stroke-width": 4*w, fill: "none"}, bl));
  });
  const ob = el("g", {id: "contacts"}, svg);
  img.observations.forEach(o => {
    if (o.contact) {
      const p = o.contact.point, n = o.contact.normal, L = 0.1 * R;
      el("circle", {cx: p[0], cy: -p[1], r: 3*w, class: "contact", fill: "#000"}, ob);
      el("line", {x1: p[0], y1: -p[1], x2: p[0] + L*n[0], y2: -(p[1] + L*n[1]),
         class: "normal", stroke: "#000", "stroke-width": 1.5*w}, ob);
    } else {
      const a = o.origin, d = o.direction;
      el("line", {x1: a[0], y1: -a[1], x2: a[0] + o.length*d[0], y2: -(a[1] + o.length*d[1]),
         class: "miss", stroke: "#999", "stroke-dasharray": 3*w, "stroke-width": w}, ob);
    }
  });
  const pg = el("g", {id: "paths"}, svg);
  (plan.paths || []).forEach((p, i) => {
    const o = p.origin, a = p.aim || [o[0] + p.length*p.direction[0], o[1] + p.length*p.direction[1]];
    el("line", {x1: o[0], y1: -o[1], x2: a[0], y2: -a[1], class: "path",
       stroke: i === 0 ? "#1f5fbf" : "#6fa8dc", "stroke-width": (i === 0 ? 2.5 : 1.2)*w}, pg);
    const t = el("text", {x: o[0], y: -o[1] - 4*w, "font-size": 7*w, class: "path-label",
       fill: "#1f5fbf"}, pg);
    t.textContent = `${i+1}: P(DM)=${(p.p_distinguishing ?? 0).toFixed(2)}` +
      (p.expected_remaining == null ? "" : `, E=${p.expected_remaining.toFixed(2)}`);
  });
  const s = img.sensor_position;
  el("rect", {x: s[0]-4*w, y: -s[1]-4*w, width: 8*w, height: 8*w, fill: "#000", id: "sensor"}, svg);
}
function tables(session, plan) {
  const hb = document.querySelector("#hypotheses tbody"); hb.innerHTML = "";
  session.hypotheses.forEach(h => {
    const tr = document.createElement("tr");
    [h.object, h.stable_pose, h.pose.x.toFixed(1), h.pose.y.toFixed(1),
     (h.pose.theta * 180 / Math.PI).toFixed(1), h.error_bound.eps_t.toFixed(1),
     h.probability.toFixed(3), h.equivalence_class].forEach((v, i) => {
      const td = document.createElement("td"); td.textContent = v;
      if (i === 0) td.className = "l"; tr.appendChild(td); });
    hb.appendChild(tr);
  });
  const pb = document.querySelector("#paths tbody"); pb.innerHTML = "";
  (plan.paths || []).forEach((p, i) => {
    const tr = document.createElement("tr");
    const f = v => v == null ? "-" : Number(v).toFixed(2);
    [i + 1, p.family, f(p.p_distinguishing), f(p.p_informative), f(p.expected_remaining),
     f(p.motion_cost)].forEach((v, j) => { const td = document.createElement("td");
      td.textContent = v; if (j === 1) td.className = "l"; tr.appendChild(td); });
    pb.appendChild(tr);
  });
}
async function refresh() {
  try {
    const session = await (await fetch(base + "?limit=200", auth)).json();
    if (shown === session.version) return;
    const [img, plan] = await Promise.all([
      fetch(base + "/image.json", auth).then(r => r.json()),
      fetch(base + "/plan?limit=5", auth).then(r => r.ok ? r.json() : {paths: []})]);
    draw(img, plan); tables(session, plan);
    document.getElementById("status").textContent = session.status;
    document.getElementById("version").textContent = session.version;
    document.getElementById("count").textContent = session.hypotheses.length;
    const notes = [];
    if (plan.truncated) notes.push("(plan truncated by its budget)");
    if (img.drawn < img.hypothesis_count) notes.push(`(drawing the ${img.drawn} most probable)`);
    document.getElementById("note").textContent = notes.join(" ");
    shown = session.version;
    document.body.dataset.version = session.version;
  } catch (err) {
    document.getElementById("note").textContent = "refresh failed: " + err;
  }
}
refresh();
setInterval(refresh, 1500);
</script>
</body></html>
"""


def _inline_hash(page: str, tag: str) -> str:
    """The CSP source for the one inline `tag` element of `page`: 'sha256-<base64>'."""
    start = page.index(f"<{tag}>") + len(tag) + 2
    body = page[start : page.index(f"</{tag}>", start)]
    return f"'sha256-{base64.b64encode(hashlib.sha256(body.encode()).digest()).decode()}'"


#: The viewer page's policy: its own inline script and style only (by hash, so no
#: injected element runs), fetches to its own origin, SVG drawn in place, no framing.
VIEW_CSP = (
    "default-src 'none'; "
    f"script-src {_inline_hash(VIEW_HTML, 'script')}; "
    f"style-src {_inline_hash(VIEW_HTML, 'style')}; "
    "connect-src 'self'; img-src 'self' data:; "
    "frame-ancestors 'none'; base-uri 'none'; form-action 'none'"
)
