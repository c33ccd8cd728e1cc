"""Scenes as files: read (a file, stdin, or a shipped scene by name: every
problem one line naming the flag, exit 2), written for a person to read, and
the shipped example scenes (texelpad/scenes/*.json, package data)."""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

from .errors import CliError

# The shipped example scenes: texelpad/scenes/<stem>.json (package data).
SCENES_PACKAGE = "texelpad.scenes"


def shipped_scenes() -> dict[str, Any]:
    """{stem: the shipped scene file (an importlib Traversable)}, sorted."""
    from importlib import resources
    found = {}
    for f in resources.files(SCENES_PACKAGE).iterdir():
        if f.name.endswith(".json") and f.is_file():
            found[f.name[:-5]] = f
    return dict(sorted(found.items()))


def read_scene_file(path: str, flag: str = "--scene") -> dict[str, Any]:
    """A scene from a JSON file; "-" reads stdin; a name with no file of
    that name is a shipped scene (`texelpad scenes` lists them: "split-4sin"
    or "split-4sin.json"). Every problem is one line naming `flag`, exit 2."""
    shown = path
    try:
        if path == "-":
            shown = "stdin"
            data = getattr(sys.stdin, "buffer", sys.stdin).read()
            text = data.decode("utf-8") if isinstance(data, bytes) else data
        else:
            f = Path(path)
            stem = path[:-5] if path.endswith(".json") else path
            shipped = {} if f.exists() or "/" in path or os.sep in path else shipped_scenes()
            if stem in shipped:
                shown = "shipped scene %s" % stem
                text = shipped[stem].read_text(encoding="utf-8")
            else:
                text = f.read_text(encoding="utf-8")
    except OSError as e:
        hint = ""
        if not Path(path).exists() and "/" not in path and os.sep not in path:
            hint = " (nor is it a shipped scene: texelpad scenes lists them)"
        raise CliError(flag, "cannot read %s: %s%s" % (path, e.strerror or e, hint)) from None
    except UnicodeDecodeError:
        raise CliError(flag, "%s is not UTF-8 text" % shown) from None
    try:
        scene = json.loads(text, parse_int=_json_int)
    except json.JSONDecodeError as e:
        raise CliError(flag, "%s is not valid JSON: %s (line %d, column %d)"
                       % (shown, e.msg, e.lineno, e.colno)) from None
    except _HugeInt as e:
        raise CliError(flag, "%s: the integer %s has %s digits, far too large for any "
                       "scene value" % (shown, e.head, e.digits)) from None
    except RecursionError:
        raise CliError(flag, "%s is nested too deeply (a scene is a few levels deep: "
                       "{\"regions\": [{\"texture\": {...}}]})" % shown) from None
    if not isinstance(scene, dict):
        raise CliError(flag, "%s: a scene is a JSON object {\"regions\": [...]}, not a %s"
                       % (shown, type(scene).__name__))
    return scene


class _HugeInt(ValueError):
    def __init__(self, text: str):
        super().__init__(text[:12])
        self.head = text[:12] + "..."
        self.digits = format(len(text.lstrip("-")), ",")


def _json_int(text: str) -> int:
    # json.loads would fail on an integer beyond Python's int->str limit
    # (4,300 digits) with a ValueError and no position; no scene value needs
    # more than 20 digits (the link carries 64 bits: protocol.INT_MAX)
    if len(text) > 40:
        raise _HugeInt(text)
    return int(text)


def pin_formats(scene: dict[str, Any], v: int = 1) -> tuple[dict[str, Any], int, int]:
    """(a copy of `scene` with "v": v in every texel texture that has no "v",
    how many were pinned, how many said their format already). A texture
    without "v" is format 2 since texelpad 0.2 (texel.gen.params.FORMAT_VERSION);
    before, it was format 1 - pinning 1 keeps an old file's texture. Only the
    shape is checked here (regions, each with a texture): the values are the
    board's to check when the scene is pushed. ValueError names what is not
    a scene."""
    import copy
    regions = scene.get("regions")
    if not isinstance(regions, list):
        raise ValueError("not a scene: expected {\"regions\": [...]}, %s"
                         % ("no \"regions\"" if regions is None
                            else "\"regions\" is a %s" % type(regions).__name__))
    out = copy.deepcopy(scene)
    pinned = said = 0
    for i, r in enumerate(out["regions"]):
        tex = r.get("texture") if isinstance(r, dict) else None
        if not isinstance(tex, dict):
            raise ValueError("regions[%d]: expected {\"start_mm\", \"end_mm\", \"texture\": {...}}"
                             % i)
        if tex.get("kind") != "texel":
            continue
        if "v" in tex:
            said += 1
        else:
            tex["v"] = v
            pinned += 1
    return out, pinned, said


# key order in a written scene (the board's dicts have no order of their own)
_FIRST = ("kind", "name", "notes", "idle_amplitude", "regions", "start_mm", "end_mm", "texture")


def _ordered(v: Any) -> Any:
    if isinstance(v, dict):
        keys = [k for k in _FIRST if k in v] + sorted(k for k in v if k not in _FIRST)
        return {k: _ordered(v[k]) for k in keys}
    if isinstance(v, (list, tuple)):
        return [_ordered(x) for x in v]
    return v


def scene_json(scene: dict[str, Any]) -> str:
    """A scene as JSON a person reads: one key a line, but each list of
    numbers (a samples region's values) on one line."""
    def fmt(v: Any, ind: str) -> str:
        if isinstance(v, dict) and v:
            inner = ind + "  "
            return "{\n%s\n%s}" % (",\n".join("%s%s: %s" % (inner, json.dumps(k), fmt(x, inner))
                                              for k, x in v.items()), ind)
        if isinstance(v, list) and v and any(isinstance(x, (dict, list)) for x in v):
            inner = ind + "  "
            return "[\n%s\n%s]" % (",\n".join(inner + fmt(x, inner) for x in v), ind)
        return json.dumps(v, allow_nan=False)
    return fmt(_ordered(scene), "") + "\n"
