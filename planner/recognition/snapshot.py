"""Snapshots of a derived session: bytes that restore it without replaying its observations.

A service keeps the newest derived state of each session beside the event log, so
that a cache miss, a restart or another host does not rebuild the interpretation
tree from the first observation. The observations stay the source of truth: a
snapshot is only a cache of what they derive. It is tagged with :func:`code_version`
(the snapshot format and a digest of this package's source), and :func:`restore`
refuses a snapshot of any other code: the caller then replays the log.

The body is a pickle, so a snapshot must come from where the code does (the
service's own database), never from a client.

>>> from planner.models.library import object_from_dict
>>> from planner.types import Contact, Observation, SensingPath, Workspace
>>> square = object_from_dict({"name": "sq", "outline": [[-1, -1], [1, -1], [1, 1], [-1, 1]]})
>>> s = Session([square], workspace=Workspace((0, 0), 10))
>>> s = s.observe(Observation(SensingPath((0, -10), (0, 1), 20), Contact((0, -1), (0, -1))))
>>> again = restore(snapshot(s))
>>> again.status == s.status, len(again.hypotheses) == len(s.hypotheses)
(True, True)
>>> restore(b"older code\\n...") is None
True
"""

from __future__ import annotations

import functools
import hashlib
import pickle
import zlib
from pathlib import Path

import numpy as np

from planner.recognition.session import Session

__all__ = ["SNAPSHOT_FORMAT", "code_version", "restore", "snapshot"]

#: Bumped when the snapshot's layout changes in a way the source digest would not show.
SNAPSHOT_FORMAT = 1


@functools.cache
def code_version() -> str:
    """The tag of snapshots this code writes and reads: format, numpy's major version
    and a digest of every source file of the planner package."""
    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    numpy_major = np.__version__.split(".")[0]
    return f"{SNAPSHOT_FORMAT}.{numpy_major}.{digest.hexdigest()[:16]}"


def snapshot(session: Session) -> bytes:
    """The derived session as bytes (its hypotheses are derived first if they were not)."""
    session.hypotheses  # noqa: B018 - a snapshot holds the derived state
    body = zlib.compress(pickle.dumps(session, protocol=pickle.HIGHEST_PROTOCOL), 1)
    return code_version().encode() + b"\n" + body


def restore(data: bytes) -> Session | None:
    """The session a :func:`snapshot` holds, or None when another code version wrote it."""
    tag, _, body = bytes(data).partition(b"\n")
    if tag.decode(errors="replace") != code_version():
        return None
    session = pickle.loads(zlib.decompress(body))  # written by this code only (see above)
    if not isinstance(session, Session):
        return None
    return session
