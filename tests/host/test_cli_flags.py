"""The texel flags are derived from the device's own parameter spec
(texel.gen.params.SPEC), declared once (texelpad.cli.texel_flags.add_texel_flags),
and the command table imports a command's module only when it runs."""
from __future__ import annotations

import subprocess
import sys

import pytest

from texel.gen.params import SPEC
from texelpad import cli
from texelpad.cli import texel_flags


def _parser_for(command: str):
    parser = cli.build_parser([command])
    sub = next(a for a in parser._actions if a.dest == "command")
    return sub.choices[command]


def _texel_flags(p) -> dict:
    return {a.dest: a for a in p._actions if a.dest in SPEC}


def test_every_spec_key_but_the_version_has_a_flag():
    assert set(texel_flags.TEXEL_KEYS) == set(SPEC) - {"v"}
    assert texel_flags.PARAM_FLAGS["band_limit_cpmm"] == "--band-limit-cpmm"


@pytest.mark.parametrize("command, keys", [
    ("render", set(SPEC) - {"v"}),
    ("push", set(SPEC) - {"v", "length_samples"}),     # a scene region sets the length
])
def test_flags_follow_the_spec(command, keys):
    flags = _texel_flags(_parser_for(command))
    # the format version is --format (1 or 2), not a ranged number flag
    fmt = flags.pop("v")
    assert fmt.option_strings == ["--format"] and fmt.choices == (1, 2) and fmt.default is None
    assert set(flags) == keys
    for key, action in flags.items():
        kind, default, lo, hi = SPEC[key]
        assert action.option_strings == [texel_flags.PARAM_FLAGS[key]]
        assert action.type is (int if kind == "i" else float)
        assert action.default is None              # unset: the device's default applies
        assert ("%g" % hi if kind == "f" else format(hi, ",")) in action.help, action.help
    if command == "render":
        assert flags["pitch_db"].required and flags["irregularity_db"].required


def test_quant_db_help_names_the_finest_grid():
    h = _texel_flags(_parser_for("render"))["quant_db"].help
    assert "0 or 0.001 .. 20" in h


def test_tiny_quant_grid_is_a_clear_error_not_a_traceback(capsys):
    # the review's case: passed validation, then the plan overflowed dividing by it
    rc = cli.main(["render", "--pitch-db", "6", "--irregularity-db", "-10",
                   "--quant-db", "1e-308"])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    assert err.startswith("texelpad render: error: --quant-db: 1e-308")


def test_commands_are_imported_only_when_they_run():
    code = ("import sys\nfrom texelpad.cli import build_parser\nbuild_parser(['tank'])\n"
            "print(sorted(m for m in sys.modules if m.startswith('texelpad.cli.')))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    # the parser's and the command's shared modules, and no other command
    assert p.stdout.strip() == ("['texelpad.cli.errors', 'texelpad.cli.parsing', "
                                "'texelpad.cli.tank']")


def test_the_table_lists_every_command_module_once():
    mods = {m for m, _, _ in cli.COMMANDS.values()}
    assert mods == {"demo", "board", "deploy", "virtual", "bench", "render", "tank", "scene", "lab",
                    "encode", "brush", "boardfile", "firmware"}
    for name, (mod, func, summary) in cli.COMMANDS.items():
        p = _parser_for(name)
        assert callable(p.get_default("func")), name
        assert summary and p.description, name


def test_format_flag_makes_a_format2_texture(tmp_path, capsys):
    out = tmp_path / "m.npy"
    assert cli.main(["render", "--pitch-db", "13", "--irregularity-db", "-10", "--seed", "3",
                     "--format", "2", "--engine", "int", "--out", str(out)]) == 0
    import numpy as np
    import texel
    want = texel.render({"pitch_db": 13, "irregularity_db": -10, "seed": 3, "v": 2}, engine="int")
    assert np.array_equal(np.load(out), np.asarray(want))
    rc = cli.main(["render", "--pitch-db", "13.0005", "--irregularity-db", "-10", "--format", "2"])
    assert rc == 2 and "--pitch-db: 13.0005 is half-way" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["render", "push"])
def test_texture_option_flags(command):
    """The texture options (texel.gen.params.OPTION_SPEC, seed 001's
    stimulus): --min-cpmm F and --phase {continuous,reset}, unset by default
    (then the texture leaves them out)."""
    flags = {a.dest: a for a in _parser_for(command)._actions}
    assert flags["min_cpmm"].option_strings == ["--min-cpmm"] and flags["min_cpmm"].type is float
    assert flags["phase"].option_strings == ["--phase"] and flags["phase"].choices == ("continuous", "reset")
    assert flags["min_cpmm"].default is None and flags["phase"].default is None
    assert "94.3396" in flags["min_cpmm"].help


def test_option_flags_render_the_option_texture(tmp_path, capsys):
    import numpy as np
    import texel
    out = tmp_path / "m.npy"
    assert cli.main(["render", "--pitch-db", "4.353", "--irregularity-db", "-4.195", "--seed", "5",
                     "--min-cpmm", "1", "--phase", "reset", "--engine", "int", "--out", str(out)]) == 0
    want = texel.render({"pitch_db": 4.353, "irregularity_db": -4.195, "seed": 5, "v": 2,
                         "min_cpmm": 1.0, "phase": "reset"}, engine="int")
    assert np.array_equal(np.load(out), np.asarray(want))
    capsys.readouterr()
    rc = cli.main(["render", "--pitch-db", "4", "--irregularity-db", "-4", "--min-cpmm", "20",
                   "--band-limit-cpmm", "10"])
    assert rc == 2 and "--min-cpmm: 20.0 must be below band_limit_cpmm 10.0" in capsys.readouterr().err
