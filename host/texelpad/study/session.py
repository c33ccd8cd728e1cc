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

A file whose last record lacks its newline (a copy cut short, an editor
that strips it) keeps that record - it is whole - and the next record is
written after a newline, never glued onto it.

One server per data folder: DataLock, an exclusive fcntl.flock on
DATA/.texelpad-lab.lock holding the holder's pid (and its web port, which
the next run on the folder uses again). The kernel lets go of it when the
process ends, however it ends; a second server on the folder is refused and
told which process holds it.

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
from .legacy import OLD_FORMATS, effective_header

NAME = re.compile(r"^[A-Za-z0-9_-]{1,40}$")
FORMAT = "texelpad-session/4"          # /1, /2, /3: older (study/legacy.py reads them)


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
                if rec.get("kind") != "session" or rec.get("format") not in (FORMAT,
                                                                              *OLD_FORMATS):
                    raise SessionError("%s: not a texelpad session file" % path)
                header = effective_header(rec)
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
        fd = os.open(self.path, os.O_RDWR | os.O_APPEND)
        try:
            size = os.fstat(fd).st_size
            # a last line without its newline (whole: open() kept it): end
            # it first, in the same write as the record
            glue = size > 0 and os.pread(fd, 1, size - 1) != b"\n"
            self._write(fd, rec, b"\n" if glue else b"")
        finally:
            os.close(fd)
        self.records.append(rec)
        return rec

    @staticmethod
    def _write(fd: int, rec: dict[str, Any], before: bytes = b"") -> None:
        try:
            line = before + (json.dumps(rec, ensure_ascii=False, allow_nan=False,
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


class DataLocked(SessionError):
    """The data folder is another server's."""


class DataLock:
    """One server per data folder: an exclusive, non-blocking fcntl.flock on
    DATA/.texelpad-lab.lock, the holder's {"pid", "http_port"?, "started"}
    written in it. The kernel drops the lock when the holder's process ends
    (a crash, SIGKILL); the file stays, so `previous` tells the next run the
    last holder's port. Where fcntl is missing (Windows) nothing is locked."""

    NAME = ".texelpad-lab.lock"

    def __init__(self, data: str | os.PathLike) -> None:
        self.path = Path(data) / self.NAME
        self.fd: int | None = None
        self.previous: dict[str, Any] = {}      # what the last holder wrote

    def acquire(self) -> "DataLock":
        try:
            import fcntl
        except ImportError:                     # (no flock: not locked)
            return self
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as e:
            raise SessionError("data folder %s: %s" % (self.path.parent, e.strerror or e)) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = _read_lock(fd)
            os.close(fd)
            pid = holder.get("pid")
            where = " on http://127.0.0.1:%d/" % holder["http_port"] \
                if isinstance(holder.get("http_port"), int) else ""
            raise DataLocked("data folder %s is in use by another texelpad lab (%s%s): stop "
                             "it, or give another --data"
                             % (self.path.parent, "process %d" % pid if isinstance(pid, int)
                                else "a process starting", where)) from None
        self.previous = _read_lock(fd)
        self.fd = fd
        self.update()
        return self

    def update(self, **info: Any) -> None:
        """Write the holder's pid (and info: its http_port) into the lock file."""
        if self.fd is None:
            return
        rec = {"pid": os.getpid(), "started": _now()}
        cur = _read_lock(self.fd)
        if cur.get("pid") == os.getpid():
            rec.update(cur)
        rec.update(info)
        raw = (json.dumps(rec) + "\n").encode()
        os.ftruncate(self.fd, 0)
        os.pwrite(self.fd, raw, 0)
        os.fsync(self.fd)

    def release(self) -> None:
        if self.fd is not None:
            os.close(self.fd)               # (closing drops the flock)
            self.fd = None


def _read_lock(fd: int) -> dict[str, Any]:
    try:
        raw = os.pread(fd, 4096, 0)
        v = json.loads(raw.decode("utf-8"))
    except (OSError, ValueError):
        return {}
    return v if isinstance(v, dict) else {}
