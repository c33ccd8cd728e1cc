"""The import rules of docs/architecture.md, checked on the source (ast: every
import statement, also those inside functions), so the layers stay visible:
the generator does not know the runtime, the runtime does not know a
backend, device code knows nothing of the host or of test doubles, pure
analysis never imports the link, the link never imports a command, and a
command imports no other command."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DEVICE = ROOT / "device" / "texel"
HOST = ROOT / "host" / "texelpad"


def _module_name(path: Path) -> str:
    base = DEVICE.parent if path.is_relative_to(DEVICE) else HOST.parent
    parts = list(path.relative_to(base).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports(path: Path) -> set[str]:
    """Every module the file imports, as absolute dotted names (relative
    imports resolved against the file's package; `from a import b` counts as
    a.b too, so submodules imported that way are seen)."""
    name = _module_name(path)
    pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[:len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.add(mod)
            out.update("%s.%s" % (mod, a.name) for a in node.names)
    return out


def modules(root: Path, sub: str = "") -> list[Path]:
    return sorted(p for p in (root / sub).rglob("*.py") if "__pycache__" not in p.parts)


def _bad(paths: list[Path], forbidden: tuple[str, ...]) -> dict[str, list[str]]:
    found = {}
    for p in paths:
        hits = sorted(m for m in imports(p) for f in forbidden if m == f or m.startswith(f + "."))
        if hits:
            found[str(p.relative_to(ROOT))] = hits
    return found


def test_the_resolver_sees_relative_imports():
    got = imports(DEVICE / "runtime" / "scene.py")
    assert "texel.gen.params" in got and "texel.make_plan" in got
    assert "texelpad.link.transport" in imports(HOST / "cli" / "common.py")


@pytest.mark.parametrize("sub, forbidden", [
    ("gen", ("texel.runtime", "texel.hw", "texel.app", "texelpad")),
    ("runtime", ("texel.hw", "texel.app", "texelpad")),
    ("hw", ("texel.runtime", "texel.gen", "texel.app", "texelpad")),
])
def test_device_layers(sub, forbidden):
    assert _bad(modules(DEVICE, sub), forbidden) == {}


def test_device_code_knows_no_host_and_no_test_doubles():
    assert _bad(modules(DEVICE), ("texelpad", "support", "tests", "fakes", "pytest")) == {}
    for p in modules(DEVICE):
        text = p.read_text(encoding="utf-8")
        assert "fakes" not in text and "ulab_standin" not in text, p


def test_numpy_only_in_the_numpy_engine_and_compat():
    users = {str(p.relative_to(DEVICE)) for p in modules(DEVICE)
             if any(m == "numpy" or m.startswith("numpy.") for m in imports(p))}
    assert users <= {"compat.py", "gen/engine_numpy.py"}, users


def test_pure_host_logic_never_imports_the_link_or_a_command():
    pure = modules(HOST, "analysis") + [HOST / "bench" / "opcount.py", HOST / "plate" / "tank.py",
                                        HOST / "deploy" / "image.py", HOST / "toolchain.py"]
    assert _bad(pure, ("texelpad.link", "texelpad.cli", "texelpad.deploy.install",
                       "serial", "mpremote")) == {}


def test_study_search_and_brush_are_pure_logic():
    """The protocols, sessions, the search and the paintbrush's analysis
    never touch the link or a web framework: only the lab's web server will
    own a Board (issue 11)."""
    pure = modules(HOST, "study") + modules(HOST, "search") + modules(HOST, "brush")
    assert pure
    assert _bad(pure, ("texelpad.link", "texelpad.cli", "texelpad.deploy", "serial", "mpremote",
                       "starlette", "fastapi", "flask", "aiohttp", "uvicorn", "http")) == {}


def test_the_link_imports_no_command():
    assert _bad(modules(HOST, "link"), ("texelpad.cli",)) == {}
    assert _bad(modules(HOST, "deploy") + modules(HOST, "bench"), ("texelpad.cli",)) == {}


def test_commands_import_no_other_command():
    cmds = [p for p in modules(HOST, "cli") if p.name not in ("__init__.py", "__main__.py")]
    for p in cmds:
        mine = _module_name(p)
        others = [m for m in imports(p) if m.startswith("texelpad.cli.")
                  and m.split(".")[2] not in ("common", mine.split(".")[-1])]
        assert others == [], (p.name, others)


def test_only_transport_imports_mpremote_and_serial():
    users = {str(p.relative_to(HOST)) for p in modules(HOST)
             if any(m.split(".")[0] in ("mpremote", "serial") for m in imports(p))}
    assert users == {"link/transport.py"}, users


def test_device_scripts_are_not_host_modules():
    # the bench scripts that run under MicroPython are package data, not importable modules
    assert not (HOST / "bench" / "device" / "__init__.py").exists()
