"""Fuzz target "flags": random command lines for `texelpad render`, `tank`
and `push` (no board: push must fail cleanly), run in-process through
texelpad.cli.main with stdout and stderr captured.

Command lines: every flag of the three commands in every spelling argparse
takes (--pitch-db V, --pitch-db=V, abbreviations, repeated, missing), with
values valid and not - numbers in every notation (6.3, 1e1, +5, 0x5, 5_0,
unicode digits, inf, nan, -1e999, 5,000 digits), SI quantities with and
without units and prefixes (390u, 390 uH, 34kHz, 56nF, -1u, 1e-320p, a
100,000-character one), engine names, output paths (writable, in a missing
directory, into a file, a directory, other suffixes), scene files (valid,
mutated, not JSON, NaN tokens, 3,000 levels deep, a 5,000-digit integer,
not UTF-8, missing, a directory), ports that are no board (missing, a
regular file, a directory, /dev/null, none at all: no board is found),
timeouts; plus junk tokens, --help, --version, unknown flags.

Properties, per command line: main() returns (or argparse exits) with 0, 1
or 2 and raises nothing else (no traceback); a failure writes exactly one
line to stderr, "texelpad ...: error: ..." (or argparse's own one line), of
at most 1,000 characters; push never succeeds without a board; a render
that succeeds with --out has written it; `tank --json` prints JSON without
NaN or infinity; --help and --version exit 0.
"""
from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path
from unittest import mock

import pytest
from hypothesis import given, strategies as st

import fuzzlib
import texelpad.link.board
import texelpad.link.transport
import texelpad.sim.virtual
from texel.gen import params as P
from texelpad import cli
from test_scene_fuzz import deep, inputs as scene_inputs

FUZZ_TARGET = "flags"
pytestmark = pytest.mark.fuzz


def _idx(draw, n: int) -> int:
    return draw(st.integers(0, 2 ** 24)) % n


# --- values as typed ------------------------------------------------------------------------

NUMBER_TEXT = ["6.3", "6", "-10", "-12.9", "0", "-0", "+5", " 5", "5 ", "1e1", "1E1", "-1e1",
               ".5", "5.", "-.5", "0x5", "5_0", "1__0", "\u0665", "\uff15", "Infinity", "inf",
               "-inf", "+inf", "nan", "-nan", "NaN", "1e999", "-1e999", "1e-999", "", " ", "-",
               "--", "5,3", "5.3.1", "9" * 5000, "1" * 50, "-" + "9" * 30, "0.0001", "1e-308",
               "2.5e-324", "19.747", "19.748", "-20", "-20.0001", "5", "5.0001", "-30", "-30.1",
               "1048576", "1048577", "4294967295", "4294967296", "-1", "0.001", "0.0009", "20",
               "20.5", "1", "1.0", "true", "None", "é", "\x00", "6.3\n", "'6.3'", "=6"]


def _num_text(draw) -> str:
    how = _idx(draw, 4)
    if how == 0:
        return draw(st.sampled_from(NUMBER_TEXT))
    if how == 1:
        return repr(draw(st.floats()))
    if how == 2:
        return str(draw(st.integers(-(2 ** 70), 2 ** 70)))
    return draw(st.text(max_size=12))


def _value_for(draw, key: str, clean: bool = False) -> str:
    """A value for a texel flag: mostly in or near its range (bounded so a
    render stays fast: no 10^6-sample maps), else anything; `clean`: in its
    range but for one in 20."""
    kind, _, lo, hi = P.SPEC[key]
    if clean and _idx(draw, 20):
        if key == "length_samples":
            return str(draw(st.integers(1, 50_000)))
        if key == "texel_samples":
            return str(draw(st.one_of(st.integers(1, 500), st.integers(1, P.TEXEL_MAX))))
        if key == "quant_db" and _idx(draw, 2):
            return "0"
        if key == "band_limit_cpmm":
            lo = 0.01
        if kind == "i":
            return str(draw(st.integers(int(lo), int(hi))))
        return repr(draw(st.floats(lo, hi, allow_nan=False)))
    if _idx(draw, 3) == 0:
        return _num_text(draw)
    if key == "length_samples":
        return str(draw(st.one_of(st.integers(1, 50_000), st.sampled_from([0, -1, P.LENGTH_MAX + 1]))))
    if key == "texel_samples":
        return str(draw(st.one_of(st.integers(1, 500), st.sampled_from([0, 1, P.TEXEL_MAX, P.TEXEL_MAX + 1]))))
    if kind == "i":
        return str(draw(st.integers(int(lo) - 2, int(min(hi, 2 ** 40)) + 2)))
    x = draw(st.floats(lo - 1, hi + 1, allow_nan=False))
    return ("%r", "%g", "%.3f", "%.17g")[_idx(draw, 4)] % x


QUANTITY_TEXT = ["390u", "390uH", "390 uH", "390 \u00b5H", "390\u03bcH", "3.9e-4", "56n", "56nF",
                 "34k", "34 kHz", "34khz", "34KHZ", "33.5e3", "1.5k", "12", "12V", "48 V", "40",
                 "-1u", "0", "0u", "-0", "1e-320p", "1e308M", "5e-324", "1.7e308", "inf", "nan",
                 "-inf", "u", "k", "", " ", "1x", "1 H", "1F", "1Hz", "1V", "1mF", "1MHz",
                 "1e-300", "1e300", "x" + "1" * 100_000, "1" * 100_000 + "x", "1" * 400,
                 "\u0661\u0662", "1_000", "0x10", "--5"]


def _quantity(draw) -> str:
    how = _idx(draw, 4)
    if how < 2:
        return draw(st.sampled_from(QUANTITY_TEXT))
    if how == 2:
        num = _num_text(draw) if _idx(draw, 3) == 0 else "%g" % draw(st.floats(1e-15, 1e9))
        return num + draw(st.sampled_from(["", " ", "p", "n", "u", "\u00b5", "m", "k", "K", "M",
                                           "G"])) + draw(st.sampled_from(["", "H", "F", "Hz", "V",
                                                                         "hz", "Ohm", "A"]))
    return draw(st.text(max_size=10))


# --- command lines --------------------------------------------------------------------------

TEXEL_FLAG_KEYS = [k for k in P.KEYS if k != "v"]


def _spell(draw, flag: str, value: str | None) -> list[str]:
    """A flag and its value as argv tokens, in one of argparse's spellings."""
    name = flag
    if _idx(draw, 6) == 0 and len(flag) > 4:                    # an abbreviation
        name = flag[:draw(st.integers(3, len(flag)))]
    if value is None:
        return [name]
    if _idx(draw, 4) == 0:
        return ["%s=%s" % (name, value)]
    return [name, value]


JUNK_TOKENS = ["--help", "-h", "--version", "--", "-", "--nope", "-x", "extra", "--pitch-db",
               "--json", "=", "-5", "-inf", "\x00", "--out", "--seed", "-L"]


def _junk(draw, argv: list[str], clean: bool = False) -> list[str]:
    if clean:
        return argv
    for _ in range(draw(st.sampled_from([0, 0, 0, 0, 1, 2]))):
        tok = draw(st.one_of(st.sampled_from(JUNK_TOKENS), st.text(max_size=8)))
        argv.insert(_idx(draw, len(argv) + 1), tok)
    return argv


class Paths:
    """Output and input paths inside one temporary directory."""

    def __init__(self, root: Path):
        self.root = root
        self.out = root / "out"
        (root / "a-file").write_text("")
        (root / "a-dir.npy").mkdir(exist_ok=True)
        (root / "scenes").mkdir(exist_ok=True)

    def reset(self) -> None:
        if self.out.exists():
            shutil.rmtree(self.out)
        self.out.mkdir()


def _out_path(draw, paths: Paths, suffixes=(".npy", ".csv", ".png")) -> str:
    how = _idx(draw, 10)
    if how < 5:
        suffix = suffixes[_idx(draw, len(suffixes))] if _idx(draw, 10) else ".png"
        if suffix == ".png" and _idx(draw, 4):      # a figure costs ~0.5 s: fewer of them
            suffix = ".npy"
        return str(paths.out / ("m" + suffix))
    return draw(st.sampled_from([
        str(paths.root / "no" / "such" / "m.npy"), str(paths.root / "a-file" / "m.npy"),
        str(paths.root / "a-dir.npy"), str(paths.out / "m.jpg"), str(paths.out / "m"),
        str(paths.out / "M.NPY"), "", ".", str(paths.out / "m\nx.csv"),
        str(paths.out / ("é" * 50 + ".csv"))]))


@st.composite
def render_argv(draw, paths: Paths):
    argv = ["render"]
    clean = _idx(draw, 2) == 0              # half of them: meant to render
    for key in TEXEL_FLAG_KEYS:
        required = key in ("pitch_db", "irregularity_db")
        if _idx(draw, 10) < ((10 if clean else 9) if required else 3):
            flag = "--" + key.replace("_", "-")
            argv += _spell(draw, flag, _value_for(draw, key, clean))
    if _idx(draw, 3) == 0:
        argv += _spell(draw, "--engine", draw(st.one_of(
            st.sampled_from(["numpy", "int", "pure", "ulab", "viper", "", "NUMPY", "int "]),
            st.text(max_size=6))))
    if _idx(draw, 3) == 0:
        argv += _spell(draw, "--out", _out_path(draw, paths))
    return _junk(draw, argv, clean)


TANK_SETS = [("-L", "-C"), ("-L", "-f"), ("-C", "-f"), ("--piezo", "-f"), ("--piezo", "-L", "-f"),
             ("--piezo", "-L")]
TANK_VALUES = {"-L": (1e-7, 1e-1, "H"), "-C": (1e-11, 1e-5, "F"), "-f": (1e2, 1e6, "Hz"),
               "--piezo": (1e-11, 1e-5, "F"), "--bus-volts": (1, 400, "V"), "--q": (1, 500, "")}


def _sane_quantity(draw, flag: str) -> str:
    lo, hi, unit = TANK_VALUES[flag]
    x = draw(st.floats(lo, hi))
    return draw(st.sampled_from(["%r", "%g", "%.3g"])) % x + draw(st.sampled_from(["", unit]))


@st.composite
def tank_argv(draw):
    argv = ["tank"]
    flags = ["-L", "-C", "-f", "--piezo", "--bus-volts", "--q", "--inductance", "--capacitance",
             "--frequency"]
    extra = [0, 0, 1, 2, 3, 4]
    if _idx(draw, 2):                       # half of them: a combination that computes
        for flag in TANK_SETS[_idx(draw, len(TANK_SETS))] + (("--bus-volts", "--q")
                                                              if _idx(draw, 2) else ()):
            argv += _spell(draw, flag, _sane_quantity(draw, flag) if _idx(draw, 10)
                           else _quantity(draw))
        flags = flags[:3]
        extra = [0] * 8 + [1, 2]
    for _ in range(draw(st.sampled_from(extra))):
        argv += _spell(draw, flags[_idx(draw, len(flags))], _quantity(draw))
    if _idx(draw, 4) == 0:
        argv += _spell(draw, "--drive", draw(st.sampled_from(["single", "bridge", "Bridge", "", "x"])))
    if _idx(draw, 3) == 0:
        argv.append("--json")
    return _junk(draw, argv, clean=len(extra) > 6)


PORTS = ["{root}/no-such-tty", "/nonexistent/ttyACM9", "", "{root}/a-file", "{root}/a-dir.npy",
         "/dev/null", "COM3", "fuzz"]


@st.composite
def scene_file(draw, paths: Paths) -> str:
    f = paths.root / "scenes" / "s.json"
    how = _idx(draw, 8)
    if how < 4:
        scene, _ = draw(scene_inputs())
        try:
            with deep():                          # scenes nested 3,000 deep
                text = json.dumps(scene)          # NaN and Infinity as JSON extensions
        except (TypeError, ValueError, RecursionError):
            text = "{}"
        f.write_text(text, encoding="utf-8")
    elif how == 4:
        f.write_text(draw(st.sampled_from([
            "", "{", "[]", "null", "{\"regions\": [}", "\ufeff{\"regions\": []}",
            "{\"regions\": [" + "{\"a\": " * 3000 + "0" + "}" * 3000 + "]}",
            "{\"regions\": " + "[" * 3000 + "]" * 3000 + "}",
            "{\"regions\": [{\"start_mm\": 0, \"end_mm\": 1, \"texture\": {\"kind\": \"texel\", "
            "\"pitch_db\": 6, \"irregularity_db\": -10, \"seed\": %s}}]}" % ("9" * 5000),
            "{\"regions\": [{\"start_mm\": NaN, \"end_mm\": Infinity}]}",
            "{\"regions\": [], \"regions\": 5}"])), encoding="utf-8")
    elif how == 5:
        f.write_bytes(draw(st.binary(max_size=40)) + b"\xff\xfe")
    elif how == 6:
        return draw(st.sampled_from([str(paths.root / "none.json"), str(paths.root / "a-dir.npy"),
                                     ""]))
    else:
        f.write_text(draw(st.text(max_size=40)), encoding="utf-8")
    return str(f)


@st.composite
def push_argv(draw, paths: Paths):
    argv = ["push"]
    clean = _idx(draw, 2) == 0              # half of them: meant to reach the board
    scene = _idx(draw, 3) == 0
    for key in TEXEL_FLAG_KEYS:
        if scene and _idx(draw, 10):
            break
        if key != "length_samples" and _idx(draw, 10) < (
                (10 if clean else 6) if key in ("pitch_db", "irregularity_db") else 2):
            argv += _spell(draw, "--" + key.replace("_", "-"), _value_for(draw, key, clean))
    if scene:
        argv += _spell(draw, "--scene", draw(st.one_of(
            scene_file(paths), st.sampled_from(["-", "split-4sin", "split-4sin.json", "gradient",
                                                "nope", "../split-4sin"]))))
    if _idx(draw, 6) == 0:
        argv += _spell(draw, "--reference", draw(st.one_of(
            st.sampled_from(["4sin", "2sin", "pink", "square", "bp-4-0.5", "4SIN", "", "x" * 100]),
            st.text(max_size=8))))
    if _idx(draw, 6) == 0:
        argv += _spell(draw, "--constant", draw(st.one_of(
            st.sampled_from(["0", "0.5", "1", "1.0000001", "-0", "nan", "inf", "-1", "", "x"]),
            st.just(_num_text(draw)))))
    if _idx(draw, 4) == 0:
        argv += _spell(draw, "--board", draw(st.sampled_from(["virtual", "pico", "", "../x", "nope"])))
    if _idx(draw, 4) == 0:
        argv.append("--json")
    if _idx(draw, 5):
        argv += _spell(draw, "--port", draw(st.sampled_from(PORTS)).format(root=paths.root))
    if _idx(draw, 3) == 0:
        argv += _spell(draw, "--timeout", draw(st.one_of(
            st.sampled_from(["0.5", "0", "-1", "nan", "inf", "1e-9", "x", ""]), st.text(max_size=5))))
    return _junk(draw, argv, clean)


# --- running one ------------------------------------------------------------------------------

STDIN = [b"", b"{}", b'{"regions": []}', b"\xff\xfe", json.dumps(
    {"regions": [{"start_mm": 0, "end_mm": 1, "texture": {"kind": "constant", "level": 0.5}}]}
).encode(), b"[" * 3000, b"{\"regions\": NaN}"]


def run(argv: list[str], stdin: bytes = b"") -> tuple[int, str, str]:
    """main(argv) in-process: (exit code, stdout, stderr); stdin holds `stdin`."""
    out, err = io.StringIO(), io.StringIO()
    fake_in = io.TextIOWrapper(io.BytesIO(stdin), encoding="utf-8")
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            mock.patch.object(sys, "stdin", fake_in):
        try:
            code = cli.main(list(argv))
        except SystemExit as e:
            code = e.code
    return code, out.getvalue(), err.getvalue()


class Broken(AssertionError):
    """A broken property: .kind says which, .argv and .err what ran."""

    def __init__(self, text: str, kind: str = "", argv=(), err: str = ""):
        super().__init__(text)
        self.kind, self.argv, self.err = kind, list(argv), err


def check(argv: list[str], paths: Paths, stdin: bytes = b"") -> str:
    command = argv[0]
    code, out, err = run(argv, stdin)
    helped = any(a in ("-h", "--help", "--version") or (len(a) > 2 and "--help".startswith(a))
                 for a in argv)
    if code not in (0, 1, 2):
        raise Broken("exit code %r (expected 0, 1 or 2); stderr: %r" % (code, err[-500:]))
    if "Traceback" in err:
        raise Broken("a traceback on stderr: %r" % err[-1000:])
    if code != 0:
        lines = err.strip().split("\n")            # (a terminal breaks lines at \n only)
        if len(lines) != 1:
            raise Broken("exit %d with %d lines on stderr (expected one): %r"
                         % (code, len(lines), err[:600]), "lines", argv, err)
        if not lines[0].startswith("texelpad") or ": error: " not in lines[0]:
            raise Broken("exit %d, the error line is not 'texelpad ...: error: ...': %r"
                         % (code, lines[0][:300]))
        if len(lines[0]) > 1000:
            raise Broken("an error line of %d characters: %r" % (len(lines[0]), lines[0][:300]))
        return "exit %d" % code
    if command == "push" and not helped:
        raise Broken("push succeeded without a board: %r" % out[:300])
    if err and not helped:
        raise Broken("exit 0 with text on stderr: %r" % err[:300])
    if command == "tank" and "--json" in argv and not helped and out.lstrip().startswith("{"):
        json.loads(out, parse_constant=lambda c: (_ for _ in ()).throw(
            Broken("tank --json printed %s" % c)))
    if command == "render" and not helped and "wrote " in out:
        written = out.rsplit("wrote ", 1)[1].strip()
        if not Path(written).exists():
            raise Broken("render said it wrote %s, which does not exist" % written)
    return "exit 0" + (" (help)" if helped else "")


@pytest.fixture(scope="module")
def paths():
    """A temporary working directory (nothing a command writes lands
    elsewhere), and no board to be found: no USB board, and no running
    virtual board (another session's must never receive a fuzzed push)."""
    root = Path(tempfile.mkdtemp(prefix="texelpad-fuzz-"))
    cwd = os.getcwd()
    os.chdir(root)
    try:
        with mock.patch.object(texelpad.link.transport, "ports", lambda: []), \
                mock.patch.object(texelpad.link.board, "ports", lambda: []), \
                mock.patch.object(texelpad.sim.virtual, "running_boards", lambda: []):
            yield Paths(root)
    finally:
        os.chdir(cwd)
        shutil.rmtree(root, ignore_errors=True)


@fuzzlib.fuzz_settings()
@given(data=st.data())
def test_flags(paths: Paths, data) -> None:
    which = ("render", "tank", "push")[data.draw(st.integers(0, 2), label="command")]
    argv = data.draw({"render": render_argv(paths), "tank": tank_argv(),
                      "push": push_argv(paths)}[which], label="argv")
    stdin = data.draw(st.one_of(st.sampled_from(STDIN), st.binary(max_size=30)), label="stdin") \
        if "-" in argv else b""
    paths.reset()
    with fuzzlib.case(FUZZ_TARGET, lambda: fuzzlib.short(argv, 300)) as s:
        with fuzzlib.watchdog(120, "a command line"):
            try:
                outcome = check(argv, paths, stdin)
            except Exception as e:          # main() raised, or a property broke
                fuzzlib.allow_known(FUZZ_TARGET, e, lambda: fuzzlib.short(argv, 600))
                outcome = "known bug"
        s.outcomes["%s: %s" % (which, outcome)] += 1
