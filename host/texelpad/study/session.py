"""Session files: every answer written as it happens, so nothing is lost.

One session = one JSON-lines file `<data>/<participant>/<protocol>-<n>.jsonl`.
The first record says what the session is (protocol, participant, config,
seed, texelpad version); each answer is one record with its time, the
question, the answer, the exact canonical scene that was playing and the
protocol's state after it. Every record is written with one write(), then
flushed and fsynced before the caller goes on: a crash (browser closed,
server killed, board unplugged, power cut) loses at most the answer being
written. Reading back drops a torn last line - one that a crash cut off -
and says so; damage anywhere else is an error, never silently skipped.

Participant ids and protocol names are plain words ([A-Za-z0-9_-], 1..40):
nothing a browser sends can name a path outside the data folder. Pure logic
and files: no link, no web framework.
"""
from __future__ import annotations

import datetime
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

from .. import __version__

NAME = re.compile(r"^[A-Za-z0-9_-]{1,40}$")
FORMAT = "texelpad-session/1"


class SessionError(ValueError):
    """A bad id or name, a damaged file, a record that cannot be written."""


def check_name(what: str, name: Any) -> str:
    if not isinstance(name, str) or not NAME.match(name):
        shown = repr(name) if isinstance(name, str) and len(name) <= 60 else type(name).__name__
        raise SessionError("%s: expected 1..40 letters, digits, '_' or '-', got %s" % (what, shown))
    return name


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="milliseconds")


@dataclass
class Session:
    path: Path
    header: dict[str, Any]
    records: list[dict[str, Any]] = field(default_factory=list)   # answers, in order
    torn: bool = False              # a torn last line was dropped when it was read

    # --- making and opening -----------------------------------------------------------
    @classmethod
    def create(cls, data: str | os.PathLike, protocol: str, participant: str,
               config: dict[str, Any], seed: int) -> "Session":
        """A new session file (never an existing one: the next free number)."""
        check_name("protocol", protocol)
        check_name("participant", participant)
        root = Path(data).resolve()
        folder = root / participant
        if folder.resolve().parent != root:
            raise SessionError("participant: %r leaves the data folder" % participant)
        folder.mkdir(parents=True, exist_ok=True)
        header = {"kind": "session", "format": FORMAT, "protocol": protocol,
                  "participant": participant, "config": config, "seed": seed,
                  "texelpad": __version__, "time": _now()}
        n = 1
        while True:
            path = folder / ("%s-%d.jsonl" % (protocol, n))
            try:
                fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            except FileExistsError:
                n += 1
                continue
            break
        s = cls(path, header)
        s._write(fd, header)
        os.close(fd)
        _fsync_dir(folder)
        return s

    @classmethod
    def open(cls, path: str | os.PathLike) -> "Session":
        """Read a session back (to resume, replay or export)."""
        path = Path(path)
        header, records, torn = None, [], False
        lines = path.read_bytes().split(b"\n")
        last = len(lines) - 1
        for i, raw in enumerate(lines):
            if not raw.strip():
                continue
            try:
                rec = json.loads(raw.decode("utf-8"))
                if not isinstance(rec, dict):
                    raise ValueError("not an object")
            except ValueError as e:
                if i == last:               # no newline after it: cut off by a crash
                    torn = True
                    break
                raise SessionError("%s: line %d is damaged (%s)" % (path, i + 1, e)) from None
            if header is None:
                if rec.get("kind") != "session" or rec.get("format") != FORMAT:
                    raise SessionError("%s: not a texelpad session file" % path)
                header = rec
            else:
                records.append(rec)
        if header is None:
            raise SessionError("%s: empty session file" % path)
        return cls(path, header, records, torn)

    # --- writing ----------------------------------------------------------------------
    def append(self, record: dict[str, Any]) -> dict[str, Any]:
        """Write one answer record (its number and time added) durably."""
        rec = dict(record)
        rec.setdefault("kind", "answer")
        rec["n"] = len(self.records)
        rec["time"] = _now()
        if self.torn:
            self._cut_torn_tail()
        fd = os.open(self.path, os.O_WRONLY | os.O_APPEND)
        try:
            self._write(fd, rec)
        finally:
            os.close(fd)
        self.records.append(rec)
        return rec

    @staticmethod
    def _write(fd: int, rec: dict[str, Any]) -> None:
        try:
            line = (json.dumps(rec, ensure_ascii=False, allow_nan=False,
                               separators=(",", ":")) + "\n").encode("utf-8")
        except (TypeError, ValueError) as e:
            raise SessionError("record is not JSON data: %s" % e) from None
        view = memoryview(line)
        while view:
            n = os.write(fd, view)
            view = view[n:]
        os.fsync(fd)

    def _cut_torn_tail(self) -> None:
        """Before appending after a crash: drop the torn line, so the file
        stays one record per line."""
        data = self.path.read_bytes()
        keep = data[: data.rfind(b"\n") + 1]
        with open(self.path, "r+b") as f:
            f.truncate(len(keep))
            f.flush()
            os.fsync(f.fileno())
        self.torn = False

    # --- reading ----------------------------------------------------------------------
    def answers(self) -> Iterator[dict[str, Any]]:
        return (r for r in self.records if r.get("kind") == "answer")

    @property
    def finished(self) -> bool:
        return any(r.get("kind") == "end" for r in self.records)


def _fsync_dir(folder: Path) -> None:
    """The new file's name is durable too (POSIX: fsync the directory)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def sessions(data: str | os.PathLike, participant: str | None = None) -> list[Path]:
    """The session files under the data folder (of one participant)."""
    root = Path(data)
    if participant is not None:
        check_name("participant", participant)
        return sorted((root / participant).glob("*.jsonl"))
    return sorted(root.glob("*/*.jsonl"))
