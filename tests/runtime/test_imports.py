"""No device code on a push's path imports an extensible built-in inside a
function. MicroPython (py/builtinimport.c process_import_at_level) never puts
a built-in module in sys.modules, and an *extensible* one (array, binascii,
json, os, time, ... : MP_REGISTER_EXTENSIBLE_MODULE, so a same-named file may
replace it) is looked for on every sys.path filesystem first, each time:
`import json` inside a function took 1.64 ms a call on the emulated RP2040
firmware (sys.path '', '.frozen', '/rom', '/rom/lib', '/lib': littlefs and
ROMFS stats), most of a push's "parse" (bench/request_parts.py). At a module's top
it is paid once. A module-level import, or `import sys` / `math` / `uctypes`
(not extensible) inside a function, is fine."""
from __future__ import annotations

import ast
from pathlib import Path

DEVICE = Path(__file__).resolve().parents[2] / "device" / "texel"

# MicroPython v1.28's extensible built-ins (grep MP_REGISTER_EXTENSIBLE_MODULE in
# py/, extmod/ and ports/rp2 of the instrument's source)
EXTENSIBLE = {"array", "binascii", "bluetooth", "collections", "cryptolib", "errno", "hashlib",
              "heapq", "io", "json", "machine", "os", "platform", "random", "re", "select",
              "socket", "string", "struct", "time", "websocket"}

# once per boot or per start, never per push or per request: (file, function)
ALLOWED = {
    ("main.py", "_config"),             # the power-up's /texelpad.json, once
    ("rom.py", "_beside"),              # where a module's data file is: once per module
                                        # (data_beside keeps it; a reference push called it
                                        # twice a region, 2.0 ms each, before it did)
    ("app.py", "default_board"),        # start() without a board name: once per start
    ("reference.py", "map_files"),      # the map files beside gen/reference: listed once
                                        # (a stock Pico's reference region; it keeps the list)
    ("compat.py", "console_reader"),    # texel.app.serve (CircuitPython): once per serve
}


def _function_imports(path: Path) -> list[tuple[str, int, str]]:
    tree = ast.parse(path.read_text(), str(path))
    out = []

    def walk(node: ast.AST, func: str | None) -> None:
        for child in ast.iter_child_nodes(node):
            name = func
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = child.name if func is None else func
            if func is not None and isinstance(child, (ast.Import, ast.ImportFrom)):
                mods = ([a.name for a in child.names] if isinstance(child, ast.Import)
                        else [child.module or ""] if not child.level else [])
                for m in mods:
                    if m.split(".")[0] in EXTENSIBLE:
                        out.append((func, child.lineno, m))
            walk(child, name)
    walk(tree, None)
    return out


def test_no_extensible_built_in_is_imported_inside_a_function():
    found = []
    for path in sorted(DEVICE.rglob("*.py")):
        rel = path.relative_to(DEVICE)
        for func, line, mod in _function_imports(path):
            if (path.name, func) not in ALLOWED:
                found.append("%s:%d %s() imports %s" % (rel, line, func, mod))
    assert not found, ("import these at the module's top (each call walks sys.path on "
                       "MicroPython):\n" + "\n".join(found))


def test_the_scan_finds_one(tmp_path):
    """The scan itself: an import in a nested function and a from-import count."""
    p = tmp_path / "probe.py"
    p.write_text("import json\ndef f():\n    def g():\n        from array import array\n"
                 "    import sys\n")
    assert _function_imports(p) == [("f", 4, "array")]
