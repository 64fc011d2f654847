"""OpenAPI links: from the answers that create a session or an object to the
operations on what they created, so that a client generator or a stateful API
tester can follow them (``$response.body#/id`` into ``session_id``, the answer's
ETag into ``If-Match``)."""

from __future__ import annotations

from typing import Any

__all__ = ["add_links"]

_SESSION_OPERATIONS = (
    "get_session",
    "add_observation",
    "get_plan",
    "get_image_svg",
    "get_image_png",
    "get_image_json",
    "get_report_json",
    "get_report_csv",
    "get_view",
)
#: Operations that act on whatever is there now and need the version they act on.
_VERSIONED = ("undo_observation", "delete_session")


def _session_links() -> dict[str, Any]:
    ident = {"session_id": "$response.body#/id"}
    links = {
        op: {"operationId": op, "parameters": ident, "description": f"{op} on this session"}
        for op in _SESSION_OPERATIONS
    }
    for op in _VERSIONED:
        links[op] = {
            "operationId": op,
            "parameters": {**ident, "header.If-Match": "$response.header.ETag"},
            "description": f"{op} at the version this answer is at",
        }
    return links


def _object_links() -> dict[str, Any]:
    name = {"name": "$response.body#/name"}
    links = {
        op: {"operationId": op, "parameters": name, "description": f"{op} of this object"}
        for op in ("get_object", "delete_object")
    }
    links["create_session"] = {
        "operationId": "create_session",
        "requestBody": {"objects": ["$response.body#/name"]},
        "description": "a session among this object alone (the other fields as wanted)",
    }
    return links


def add_links(schema: dict[str, Any]) -> dict[str, Any]:
    """`schema` with links on the 2xx answers of the creating operations."""
    by_id = {
        op["operationId"]: op
        for item in schema.get("paths", {}).values()
        for op in item.values()
        if isinstance(op, dict) and "operationId" in op
    }
    session = _session_links()
    wanted = {
        "create_session": (("201",), session),
        "add_observation": (("201",), session),
        "get_session": (("200",), session),
        "create_object": (("201", "200"), _object_links()),
        "import_mesh": (("201", "200"), _object_links()),
    }
    for op_id, (statuses, links) in wanted.items():
        for status in statuses:
            response = by_id.get(op_id, {}).get("responses", {}).get(status)
            if response is not None:
                response["links"] = links
    return schema
