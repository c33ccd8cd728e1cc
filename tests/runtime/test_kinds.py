"""The region kinds' registry (device/texel/runtime/kinds/): the names and
the modules agree, every module holds what scene.py and the host ask of it
(kinds/__init__.py lists it), no host or device file outside a kind's module
decides by a kind's name what the kind's module knows, and
docs/architecture.md's list of files for a new kind is true."""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from texel.runtime import kinds, scene as S

ROOT = Path(__file__).resolve().parents[2]
KINDS_DIR = ROOT / "device" / "texel" / "runtime" / "kinds"
D = {"positions": 19200, "dx_um": 5.3}
INTERFACE = ("NAME", "KEYS", "OPTIONS", "SHARED", "check", "need", "block", "store", "fill",
             "describe", "words", "label")
# one valid texture of each kind, the smallest
SMALLEST = {"texel": {"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9},
            "reference": {"kind": "reference", "name": "4sin"},
            "constant": {"kind": "constant", "level": 0.25},
            "samples": {"kind": "samples", "values": [0.0, 0.5, 1.0]},
            "brush": None,                      # tests/brush/ (190 numbers)
            "bump": {"kind": "bump"}}


def test_the_names_are_the_modules():
    mods = sorted(p.stem for p in KINDS_DIR.glob("*.py") if p.stem != "__init__")
    assert sorted(kinds.NAMES) == mods
    assert S.KINDS == kinds.NAMES


@pytest.mark.parametrize("name", kinds.NAMES)
def test_every_kind_holds_the_interface(name):
    m = kinds.get(name)
    missing = [a for a in INTERFACE if not hasattr(m, a)]
    assert not missing, "%s lacks %s (kinds/__init__.py lists them)" % (name, missing)
    assert m.NAME == name and m.KEYS[0] == "kind"
    for f in getattr(m, "FIELDS", ()):
        key, t, lo, hi, default, label = f
        assert key in m.KEYS and t in ("number", "int", "word") and label


@pytest.mark.parametrize("name", [n for n in kinds.NAMES if SMALLEST.get(n)])
def test_a_region_of_every_kind_builds_describes_and_has_words(name):
    sc = S.build(S.validate({"regions": [{"start_mm": 0, "end_mm": 10,
                                          "texture": SMALLEST[name]}]}, D), D)
    d = sc.describe()["regions"][0]
    assert d["kind"] == name
    assert kinds.words(d).startswith(name) and kinds.label(d).startswith(name)
    assert kinds.label_of(sc.source["regions"][0]["texture"]) == kinds.label(d)


def test_an_unknown_kind_is_a_name_not_a_crash():
    assert kinds.words({"kind": "chirp", "start": 0}) == "chirp"
    with pytest.raises(ValueError, match="unknown kind 'chirp'"):
        kinds.get("chirp")


# Where a kind's name may still be compared outside its module: the editor's
# own hand-made forms, the study's and the link's knowledge of texel
# textures (what they are about), samples uploads (the link's data path).
# Every other site asks the kind's module: a forgotten kind is no KeyError.
def _label_chains(path: Path) -> list[str]:
    """Functions that compare a texture's kind with 3 or more kind names."""
    out = []
    tree = ast.parse(path.read_text())
    for fn in ast.walk(tree):
        if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        names = set()
        for n in ast.walk(fn):
            if isinstance(n, ast.Compare):
                for c in [n.left] + list(n.comparators):
                    if isinstance(c, ast.Constant) and c.value in kinds.NAMES:
                        names.add(c.value)
        if len(names) >= 3:
            out.append("%s:%s" % (path.relative_to(ROOT), fn.name))
    return out


def test_no_kind_by_kind_chains_outside_the_kinds():
    files = [p for p in (ROOT / "host").rglob("*.py")] + \
            [p for p in (ROOT / "device").rglob("*.py") if KINDS_DIR not in p.parents]
    chains = [c for p in files for c in _label_chains(p)]
    # the editor resolves its hand-made forms (web/editor.py HAND_MADE; a new kind needs none);
    # a study's trial list words the study's own summaries of its textures ("what" a
    # samples map is: study/describe.py), which only the study's protocols make
    assert sorted(chains) == ["host/texelpad/study/describe.py:texture_text",
                              "host/texelpad/web/editor.py:resolve"], chains


def test_the_architecture_doc_lists_the_files_of_a_new_kind():
    doc = (ROOT / "docs" / "architecture.md").read_text()
    m = re.search(r"- A new scene region kind:(.*?)\n- ", doc, re.S)
    assert m, "docs/architecture.md: no 'A new scene region kind' entry"
    entry = m.group(1)
    for must in ("device/texel/runtime/kinds/<name>.py", "kinds.NAMES",
                 "tests/runtime/test_kind_<name>.py", "tools/gen_package_json.py"):
        assert must in entry, must
    for p in re.findall(r"`((?:device|host|tests|tools|docs)/[^`<>]+)`", entry):
        assert (ROOT / p).exists(), p
