"""Study configs: files under version control that say what a session runs -
its protocol, the protocol's config (textures, trials), a reference, a seed.
The shipped ones are in texelpad/study/configs/*.json (package data); a lab
adds its own folder (`texelpad lab --configs DIR`), whose files of the same
name win. A session's file records the config it ran (and the file's name),
so a config edited later never changes what a session was.

    {"protocol": "pursuit", "title": "...", "note": "..."?, "reference": {...}?,
     "seed": 1234?, "config": {...}}

Every file is checked when listed: the protocol must start from it (the
protocol's own Config checks), so a broken file is named with the reason
instead of failing a participant's session later - a file that is not JSON,
not UTF-8, over FILE_MAX or nested too deep for the parser too (never a
traceback). Pure logic and files.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from . import protocols
from .session import SessionError, check_name

SHIPPED = Path(__file__).with_name("configs")
KEYS = {"protocol", "title", "note", "reference", "seed", "config"}
FILE_MAX = 1 << 20          # bytes: a config is a few hundred; a larger file is a mistake


def check(name: str, c: Any) -> dict[str, Any]:
    """A config object checked as a file is (SessionError says why): its keys,
    protocol, seed, and that the protocol starts from it."""
    if not isinstance(c, dict):
        raise SessionError("config %s: expected a JSON object" % name)
    bad = sorted(set(c) - KEYS)
    if bad:
        raise SessionError("config %s: unknown key %r (allowed: %s)"
                           % (name, bad[0], ", ".join(sorted(KEYS))))
    if c.get("protocol") not in protocols.PROTOCOLS:
        raise SessionError("config %s: protocol must be one of %s, got %r"
                           % (name, ", ".join(protocols.PROTOCOLS), c.get("protocol")))
    seed = c.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)
                             or not 0 <= seed < 1 << 31):
        raise SessionError("config %s: seed must be an int in [0, 2^31), got %r" % (name, seed))
    conf = c.get("config", {})
    if not isinstance(conf, dict):
        raise SessionError("config %s: config must be an object" % name)
    try:
        protocols.start(c["protocol"], conf, seed or 0)
    except (TypeError, ValueError) as e:
        raise SessionError("config %s: %s" % (name, e)) from None
    ref = c.get("reference")
    if ref is not None and not isinstance(ref, dict):
        raise SessionError("config %s: reference must be a texture object" % name)
    return c


def available(extra: str | Path | None = None) -> dict[str, dict[str, Any]]:
    """name -> config, the shipped ones and then extra's (same name: extra
    wins). A file that does not load is listed with its "error"."""
    out: dict[str, dict[str, Any]] = {}
    for folder in (SHIPPED, Path(extra) if extra else None):
        if folder is None:
            continue
        if not folder.is_dir():
            raise SessionError("configs: %s is not a folder" % folder)
        for path in sorted(folder.glob("*.json")):
            name = path.stem
            try:
                check_name("config", name)
                if path.stat().st_size > FILE_MAX:
                    raise SessionError("config %s: over %d bytes" % (name, FILE_MAX))
                out[name] = check(name, json.loads(path.read_text(encoding="utf-8")))
                out[name]["file"] = str(path)
            except (OSError, ValueError) as e:
                out[name] = {"error": str(e), "file": str(path)}
            except RecursionError:      # (json nests by recursion: a 50,000-deep file)
                out[name] = {"error": "config %s: nests too deep to be a config" % name,
                             "file": str(path)}
    return out


def load(name: Any, extra: str | Path | None = None) -> dict[str, Any]:
    check_name("config", name)
    c = available(extra).get(name)
    if c is None:
        raise SessionError("config: no %r (known: %s)" % (name, ", ".join(available(extra))))
    if "error" in c:
        raise SessionError(c["error"])
    return c
