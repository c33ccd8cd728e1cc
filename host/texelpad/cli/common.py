"""What every texelpad command shares: exit codes, the one-line error, the
texel parameter flags (derived from the device's own parameter spec,
texel.gen.params.SPEC), argument types, the board connection and the
progress bar.

Errors in what the user typed print one line naming the flag and exit 2 (no
traceback); failures of the world (a file that cannot be written, no board,
a lost link) exit 1.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
import tempfile
from pathlib import Path
from typing import Any, NoReturn

from texel.gen.params import FORMAT_NEW, KEYS as TEXEL_SPEC_KEYS, QUANT_DB_MIN, SPEC as TEXEL_SPEC

from ..link.transport import DeviceError, LinkError

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2


class CliError(Exception):
    """A bad command-line value: printed as one line, exit 2."""

    def __init__(self, flag: str, message: str, code: int = EXIT_USAGE):
        super().__init__("%s: %s" % (flag, message) if flag else message)
        self.code = code


# What argparse takes for a negative number (a flag's value, not a flag): its
# own -5 and -.5, and also -1e5, -inf, -nan and quantities such as -1u (refused
# by their flag's type with one clear line), so `--pitch-db -inf` reaches the
# flag's check instead of "expected one argument". No texelpad flag looks like
# a negative number, so nothing is shadowed.
NEGATIVE_NUMBER = re.compile(r"^-(\d|\.\d|inf$|infinity$|nan$)", re.IGNORECASE)


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (plus a hint), exit 2, and
    negative numbers of every form are values (NEGATIVE_NUMBER)."""

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        # a value echoed by argparse is cut: `--seed 999...` of 5,000 digits
        # ("invalid int value: '999...'") stays one short line
        message = _LONG_QUOTED.sub(lambda m: _show(m.group(1)), message)
        # an argument as typed may hold a line break: the error stays one line
        message = _CONTROL.sub(lambda m: repr(m.group())[1:-1], message)
        self.exit(EXIT_USAGE, "%s: error: %s (see: %s --help)\n" % (self.prog, message, self.prog))


_LONG_QUOTED = re.compile(r"'([^'\n]{41,})'")
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


# --- the texel parameter flags --------------------------------------------------------
# One flag per key of texel.gen.params.SPEC (the format version "v" is
# --format): --pitch-db for pitch_db, typed and ranged by the spec; the
# meaning of each key is the only thing written here.
TEXEL_MEANING = {
    "pitch_db": ("DB", "central pitch, 10*log10(P / 1 cycle/mm)"),
    "irregularity_db": ("DB", "irregularity, 10*log10(sigma / 1 decade)"),
    "texel_samples": ("N", "samples per texel (5.3 um each)"),
    "length_samples": ("N", "map length in samples of 5.3 um"),
    "quant_db": ("DB", "quantize log pitch to this grid, dB (0 = off)"),
    "seed": ("N", "random seed"),
    "gain": ("G", "map scale"),
    "band_limit_cpmm": ("F", "clamp drawn pitches to at most F cycles/mm (default: faithful, "
                             "pitches above Nyquist alias as in the original)"),
}
# in the spec's own order (texel.gen.params.KEYS); a new spec key needs a meaning here
TEXEL_KEYS = tuple(k for k in TEXEL_SPEC_KEYS if k != "v")
# texel parameter key -> its flag (error messages name the flag, not the key)
PARAM_FLAGS = {k: "--" + k.replace("_", "-") for k in TEXEL_KEYS}
PARAM_FLAGS["engine"] = "--engine"
PARAM_FLAGS["v"] = "--format"
FORMAT_HELP = ("texture format: 2 = the integer plan (default), the same texture bit for bit "
               "on every board and ~25x faster to start on an RP2040 (pitch, irregularity and "
               "quantization on a 0.001 dB grid); 1 = the lab's float plan, its exact "
               "generator (a texture saved without a format is format 1); docs/generator.md")


def _range_text(key: str) -> str:
    """"-20 .. 19.747", "0 or 0.001 .. 20, default 0": the spec's range."""
    kind, default, lo, hi = TEXEL_SPEC[key]

    def num(v: float) -> str:
        return format(v, ",") if kind == "i" else "%g" % v
    low = "0 or %s" % num(QUANT_DB_MIN) if key == "quant_db" else num(lo)
    text = "%s .. %s" % (low, num(hi))
    return text if default is None else text + ", default %s" % num(default)


def add_texel_flags(group: Any, keys: tuple[str, ...] = TEXEL_KEYS,
                    required: tuple[str, ...] = ()) -> None:
    """Add --<key> flags for these texel keys to a parser or argument group."""
    for key in keys:
        kind, _, _, _ = TEXEL_SPEC[key]
        metavar, meaning = TEXEL_MEANING[key]
        group.add_argument(PARAM_FLAGS[key], dest=key, type=int if kind == "i" else float,
                           metavar=metavar, required=key in required,
                           help="%s; %s" % (meaning, _range_text(key)))
    group.add_argument("--format", dest="v", type=int, choices=(1, 2), help=FORMAT_HELP)


def _show(text: str, n: int = 40) -> str:
    """repr(text), cut to n characters: error lines stay one short line."""
    return repr(text) if len(text) <= n else repr(text[:n]) + "... (%s characters)" % format(
        len(text), ",")


def render_params(args: argparse.Namespace) -> dict[str, Any]:
    """The texel parameter dict from the flags that were given."""
    params: dict[str, Any] = {}
    for key in TEXEL_KEYS + ("v",):
        v = getattr(args, key, None)
        if v is not None:
            params[key] = v
    if params and "v" not in params:
        params["v"] = FORMAT_NEW        # a new texture: format 2 unless --format says
    return params


def device_error(e: ValueError) -> CliError:
    """A device ValueError ("pitch_db: nan is not finite ...") as a CliError
    naming the flag instead of the parameter key."""
    text = str(e)
    key, sep, rest = text.partition(": ")
    if sep and key in PARAM_FLAGS:
        return CliError(PARAM_FLAGS[key], rest)
    missing = "missing required key '"
    if text.startswith(missing):
        key, _, more = text[len(missing):].partition("'")
        if key in PARAM_FLAGS:
            return CliError(PARAM_FLAGS[key], "required%s" % more)
    return CliError("", text)


def csv_list(text: str) -> list[str]:
    items = [s.strip() for s in text.split(",")]
    if not all(items):
        raise argparse.ArgumentTypeError("expected a comma-separated list, got %r" % text)
    return items


def positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError("invalid int value: %r" % text) from None
    if v < 1:
        raise argparse.ArgumentTypeError("must be >= 1, got %d" % v)
    return v


def check_output(flag: str, path: str, suffixes: tuple[str, ...] = ()) -> Path:
    """Check an output file BEFORE the work that fills it: its suffix is one
    of `suffixes` (case-insensitive; any when empty) - else one line naming
    the flag, exit 2 - and its directory exists and takes a new file (a probe
    file is made and removed there) - else one line, exit 1. An existing
    special file (/dev/stdout, a FIFO) is taken as it is."""
    out = Path(path)
    try:
        special = out.exists() and not out.is_file() and not out.is_dir()
    except OSError:
        special = False
    if special:
        return out
    if suffixes and out.suffix.lower() not in suffixes:
        raise CliError(flag, "unsupported file type %r for %s (use %s)"
                       % (out.suffix or out.name, _show(path), ", ".join(suffixes)))
    parent = out.parent if str(out.parent) else Path(".")

    def fail(why: str) -> CliError:
        return CliError(flag, "cannot write %s: %s" % (path, why), EXIT_FAIL)
    if out.is_dir():
        raise fail("it is a directory")
    if not parent.is_dir():
        raise fail("no such directory %s" % parent if not parent.exists()
                   else "%s is not a directory" % parent)
    if out.exists() and not os.access(out, os.W_OK):
        raise fail("permission denied")
    try:
        fd, probe = tempfile.mkstemp(prefix=".texelpad-", dir=parent)
    except OSError as e:
        raise fail(e.strerror or str(e)) from None
    os.close(fd)
    try:
        os.unlink(probe)
    except OSError:
        pass
    return out


def write_output(flag: str, path: str, write: Any) -> None:
    """Run write() (which writes `path`); a failure of the filesystem is one
    line naming the flag and the path, exit 1."""
    try:
        write()
    except OSError as e:
        raise CliError(flag, "cannot write %s: %s" % (path, e.strerror or e), EXIT_FAIL) from None


def _stderr(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def positive_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError("invalid number: %r" % text) from None
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError("must be a finite number > 0, got %s" % text)
    return v


def _port_arg(p: argparse.ArgumentParser, help_none: str) -> None:
    p.add_argument("--port", metavar="PORT",
                   help="the board's serial port (/dev/ttyACM0, COM3, or a virtual board's "
                        "/dev/pts/N); default: %s" % help_none)
    p.add_argument("--timeout", type=positive_float, default=10.0, metavar="S",
                   help="seconds to wait for the board to answer (default 10)")


def _fail(e: LinkError) -> CliError:
    """A link/board error as a CliError: the board's refusal of what the user
    asked is a usage error (2), the rest a failure (1)."""
    if isinstance(e, DeviceError):
        return CliError("", "the board refused it: %s" % e, EXIT_USAGE)
    return CliError("", str(e), EXIT_FAIL)


def _connect(args: argparse.Namespace, check: bool = True, import_image: bool = True) -> Any:
    from ..link.board import connect
    try:
        return connect(args.port, timeout=args.timeout, check=check, import_image=import_image)
    except LinkError as e:
        raise _fail(e) from None


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


def _value_error(e: Exception, from_flags: bool) -> CliError:
    """A refused parameter: name the flag when it came from one."""
    text = str(e)
    if from_flags:
        path, sep, rest = text.partition(": ")
        key = path.rsplit(".", 1)[-1]
        if sep and path.startswith("regions[0].texture.") and key in PARAM_FLAGS:
            return CliError(PARAM_FLAGS[key], rest)
        missing = "missing required key '"
        if path == "regions[0].texture" and rest.startswith(missing):
            key, _, more = rest[len(missing):].partition("'")
            if key in PARAM_FLAGS:
                return CliError(PARAM_FLAGS[key], "required%s" % more)
    prefix = "the board refused it: " if isinstance(e, DeviceError) else ""
    return CliError("--scene" if not from_flags else "", prefix + text)


class ProgressBar:
    """Upload progress on stderr: a redrawn bar on a terminal, a line per
    file otherwise (logs, CI)."""

    def __init__(self, stream: Any = None, width: int = 30, label: str = "deploy"):
        self.stream = stream or sys.stderr
        self.label = label
        self.tty = self.stream.isatty()
        self.width = width
        self.last = None

    def __call__(self, done: int, total: int, name: str) -> None:
        frac = done / total if total else 1.0
        if self.tty:
            n = int(frac * self.width)
            self.stream.write("\r[%s%s] %3d%% %7s / %s bytes  %-32s" % (
                "#" * n, "." * (self.width - n), frac * 100, format(done, ","),
                format(total, ","), name[-32:]))
            self.stream.flush()
        elif name != self.last:
            self.stream.write("%s: %3d%% %s\n" % (self.label, frac * 100, name))
        self.last = name

    def end(self) -> None:
        if self.tty and self.last is not None:
            self.stream.write("\n")


def _one_board(args: argparse.Namespace) -> None:
    """No --port: the one board there is, a running `texelpad virtual`
    included (connect() itself only knows USB boards)."""
    if getattr(args, "port", None) is not None:
        return
    from ..link.transport import ports
    from ..sim.virtual import running_boards
    found = [p["port"] for p in ports()] + [e["port"] + " (virtual)" for e in running_boards()]
    if len(found) > 1:
        raise CliError("--port", "%d boards found (%s): say which with --port"
                       % (len(found), ", ".join(found)), EXIT_FAIL)
    if found:
        args.port = found[0].split(" ")[0]


def not_running(port: str, hint: str = "texelpad push --board NAME starts it") -> CliError:
    """texelpad is not running on the board: a state of the world, not a
    bad flag (exit 1), in the same words from every command."""
    return CliError("", "texelpad is not running on %s (%s)" % (port, hint), EXIT_FAIL)


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


def write_atomic(path: str, text: str) -> None:
    """Write text to path through a temporary file beside it, renamed over
    it: readers see the old file or the new one, never half of one. A
    special file (/dev/stdout, a FIFO) is written as it is."""
    out = Path(path)
    if out.exists() and not out.is_file():
        with open(out, "w", encoding="utf-8") as f:
            f.write(text)
        return
    parent = out.parent if str(out.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix="." + out.name + ".", suffix=".tmp", dir=parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        # mkstemp makes 0600: give the file the mode a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, out)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
