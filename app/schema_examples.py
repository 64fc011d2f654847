"""Requests a client can send as they are (the default sensor and safe circle),
given in the OpenAPI schema: the docs page shows them and API testers start from
them, where a random outline or mesh is almost never a valid one."""

from __future__ import annotations

__all__ = ["BOX_OFF", "OBJECT_EXAMPLES", "OBSERVATION_EXAMPLES", "SESSION_EXAMPLES"]

_PLATE = {"name": "plate", "outline": [[0, 0], [60, 0], [60, 40], [0, 40]]}
OBJECT_EXAMPLES = {"examples": [_PLATE]}
SESSION_EXAMPLES = {
    "examples": [{"objects": [_PLATE], "sensor": {"position_error": 1, "normal_error": 0.05}}]
}
OBSERVATION_EXAMPLES = {
    "examples": [
        {
            "path": {"origin": [200, 0], "direction": [-1, 0], "length": 400},
            "contact": {"point": [20, 0], "normal": [1, 0]},
        },
        {"path": {"origin": [0, 200], "direction": [0, -1], "length": 400}, "contact": None},
    ]
}
#: A 60 x 40 x 20 box in OFF (text), sent with file_type=off: it lies on any face.
BOX_OFF = (
    "OFF\n8 6 0\n"
    "0 0 0\n60 0 0\n60 40 0\n0 40 0\n0 0 20\n60 0 20\n60 40 20\n0 40 20\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n"
)
