"""See and hear the playing scene (issue 11, point 5): the display strip and
the virtual board's finger. routes(lab) -> the Starlette routes server.py
mounts. (To be filled: GET /api/strip, POST /api/finger.)"""
from __future__ import annotations

from typing import Any


def routes(lab: Any) -> list:
    return []
