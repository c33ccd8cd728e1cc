"""The import rules of docs/architecture.md, checked on the source (ast: every
import statement, also those inside functions), so the layers stay visible:
the generator does not know the runtime, the runtime does not know a
backend, device code knows nothing of the host or of test doubles, pure
analysis never imports the link, the link never imports a command, a
command imports no other command, and the host's layers (a package each)
import each other only downwards, in no cycle (issue 23)."""
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
    got = imports(DEVICE / "runtime" / "kinds" / "texel.py")     # from ... (three dots)
    assert "texel.gen.params" in got and "texel.make_plan" in got
    assert "texelpad.link.transport" in imports(HOST / "cli" / "connection.py")


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
                                        HOST / "plate" / "spice.py",
                                        HOST / "image.py", HOST / "toolchain.py"]
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
    """A command's module (a row of cli.COMMANDS) imports the shared modules
    of cli/ (errors, parsing, connection, ...) but no other command's; a
    shared module imports no command's."""
    from texelpad.cli import COMMANDS
    commands = {mod for mod, _, _ in COMMANDS.values()}
    shared = {p.stem for p in modules(HOST, "cli")} - commands - {"__init__", "__main__"}
    assert {"errors", "parsing", "connection"} <= shared, shared
    for p in modules(HOST, "cli"):
        if p.stem in ("__init__", "__main__"):
            continue
        others = sorted({m.split(".")[2] for m in imports(p) if m.startswith("texelpad.cli.")}
                        & (commands - {p.stem}))
        assert others == [], (p.name, others)


def test_only_transport_imports_mpremote_and_serial():
    users = {str(p.relative_to(HOST)) for p in modules(HOST)
             if any(m.split(".")[0] in ("mpremote", "serial") for m in imports(p))}
    assert users == {"link/transport.py"}, users


def test_device_scripts_are_not_host_modules():
    # the bench scripts that run under MicroPython are package data, not importable modules
    assert not (HOST / "bench" / "device" / "__init__.py").exists()


# --- the research benchmarks: the repository's top-level bench/, not the installed package -------
BENCH = ROOT / "bench"


def test_texelpad_bench_is_what_the_bench_commands_run():
    """Every module of texelpad.bench is reached from the commands (cli/bench.py:
    texelpad bench | bench-refresh | bench-link), so the package ships no research
    benchmark (those are bench/, below)."""
    todo = [m for m in imports(HOST / "cli" / "bench.py") if m.startswith("texelpad.bench.")]
    reached: set[str] = set()
    while todo:
        m = todo.pop()
        path = HOST.parent.joinpath(*m.split(".")).with_suffix(".py")
        if m in reached or not path.is_file():
            continue
        reached.add(m)
        todo += [n for n in imports(path) if n.startswith("texelpad.bench.")]
    shipped = {_module_name(p) for p in modules(HOST, "bench") if "device" not in p.parts}
    assert shipped - {"texelpad.bench"} <= reached, sorted(shipped - reached)


def test_the_research_benchmarks_import_texelpad_as_a_user_and_nothing_imports_them():
    """bench/ (python -m bench.NAME from the repository root) imports texelpad by its
    absolute names and never a command; nothing in texel or texelpad imports it."""
    assert (BENCH / "__init__.py").is_file() and modules(BENCH)
    for p in modules(BENCH):
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level:
                assert node.level == 1, (p.name, node.lineno)          # bench's own modules
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            assert not any(n == "texelpad.cli" or n.startswith("texelpad.cli.")
                           for n in names), (p.name, node.lineno)
    users = {str(p.relative_to(ROOT)) for p in modules(HOST) + modules(DEVICE)
             if any(m == "bench" or m.startswith("bench.") for m in imports(p))}
    assert users == set(), users


# --- the host's layers as a graph (issue 23) -----------------------------------------------------
# One node per unit of docs/architecture.md's table: a package of host/texelpad (texelpad.link,
# texelpad.study, ...) or a top-level module (texelpad.toolchain); texelpad.image is a unit
# of its own, as in the table (the offline image, below the firmware that is built from it; the
# rest of deploy writes it over the link and repairs a ROMFS with the firmware's payload). Every
# import counts, also one inside a function: a lazy import still makes the importer depend on the
# module (the two cycles of issue 23 hid inside functions).

UNITS: tuple[str, ...] = ()          # modules that are a unit of their own, not their package's

# What each unit may import (besides texel and third-party libraries): docs/architecture.md's
# "What may import what". The table itself must be a layering (acyclic), checked below.
MAY_IMPORT: dict[str, set[str]] = {
    "texelpad.toolchain": set(),
    "texelpad.plate": set(),
    "texelpad.scenes": set(),                   # package data: the shipped example scenes
    "texelpad.space": set(),
    # (the demo figure draws what the plate plays: plate.tank's envelope, pure arithmetic)
    "texelpad.analysis": {"texelpad.plate"},
    "texelpad.image": {"texelpad.toolchain"},
    "texelpad.link": {"texelpad.toolchain"},
    "texelpad.search": {"texelpad.space", "texelpad.analysis"},
    "texelpad.study": {"texelpad.space", "texelpad.search", "texelpad.analysis"},
    "texelpad.brush": {"texelpad.analysis", "texelpad.space", "texelpad.search", "texelpad.study"},
    "texelpad.firmware": {"texelpad.image", "texelpad.toolchain"},
    "texelpad.deploy": {"texelpad.image", "texelpad.firmware", "texelpad.link",
                        "texelpad.toolchain"},
    "texelpad.sim": {"texelpad.link", "texelpad.deploy", "texelpad.image",
                     "texelpad.firmware", "texelpad.toolchain"},
    "texelpad.web": {"texelpad.link", "texelpad.study", "texelpad.search", "texelpad.brush",
                     "texelpad.space", "texelpad.analysis", "texelpad.scenes", "texelpad.toolchain"},
}
_BELOW_BENCH = set(MAY_IMPORT)
MAY_IMPORT["texelpad.bench"] = set(_BELOW_BENCH)                     # everything but a command
MAY_IMPORT["texelpad.cli"] = _BELOW_BENCH | {"texelpad.bench"}
MAY_IMPORT["texelpad.__main__"] = {"texelpad.cli"}


def _unit(dotted: str) -> str | None:
    """The unit a module belongs to; None for anything outside texelpad and
    for the root package itself (texelpad/__init__.py: __version__ and lazy
    entry points, see test_the_root_package_imports_nothing_when_imported)."""
    parts = dotted.split(".")
    if parts[0] != "texelpad" or len(parts) == 1:
        return None
    for u in UNITS:
        if dotted == u or dotted.startswith(u + "."):
            return u
    return ".".join(parts[:2])


def _is_module(dotted: str) -> bool:
    rel = Path(*dotted.split(".")[1:])
    return (HOST / rel).with_suffix(".py").is_file() or (HOST / rel / "__init__.py").is_file()


def import_edges(path: Path) -> list[tuple[str, int]]:
    """(imported texelpad module, line) for every import statement of the
    file, wherever it stands (module level, a function, a method, a try).
    `from a import b` is a.b when b is a module, a otherwise; `from texelpad
    import __version__` reads the root's constant and is no edge."""
    name = _module_name(path)
    pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[:len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            for a in node.names:
                sub = "%s.%s" % (mod, a.name)
                if mod == "texelpad" and a.name == "__version__":
                    continue
                out.append((sub if _is_module(sub) else mod, node.lineno))
    return [(m, line) for m, line in out if m.split(".")[0] == "texelpad"]


def host_graph() -> dict[str, dict[str, list[str]]]:
    """unit -> imported unit -> ["file:line", ...] (imports within a unit left out)."""
    graph: dict[str, dict[str, list[str]]] = {}
    for p in modules(HOST):
        src = _unit(_module_name(p))
        if src is None:
            continue
        graph.setdefault(src, {})
        for mod, line in import_edges(p):
            dst = _unit(mod)
            where = "%s:%d" % (p.relative_to(HOST), line)
            if dst is not None and dst != src and where not in graph[src].get(dst, ()):
                graph[src].setdefault(dst, []).append(where)
    return graph


def cycles(graph: dict[str, dict]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan), each
    sorted: every cycle of the graph lies inside one of them."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _explain(graph: dict[str, dict[str, list[str]]], comp: list[str]) -> str:
    return "; ".join("%s -> %s (%s)" % (a, b, ", ".join(graph[a][b]))
                     for a in comp for b in sorted(graph.get(a, {})) if b in comp)


def test_the_graph_sees_imports_inside_functions():
    g = host_graph()
    # cli/virtual.py and cli/demo.py open a board only when the command runs
    assert "texelpad.sim" in g["texelpad.cli"] or "texelpad.link" in g["texelpad.cli"]
    assert "deploy/romfs_install.py:51" in g["texelpad.deploy"]["texelpad.firmware"]  # in a function
    assert cycles({"a": {"b": []}, "b": {"c": []}, "c": {"a": []}, "d": {"a": []}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b": []}, "b": {}}) == []


def test_the_host_packages_import_each_other_in_no_cycle():
    g = host_graph()
    found = cycles(g)
    assert found == [], "import cycles among host packages: " + " | ".join(
        _explain(g, c) for c in found)


def test_the_documented_layers_are_a_layering():
    assert cycles({k: dict.fromkeys(v) for k, v in MAY_IMPORT.items()}) == []
    on_disk = {_unit(_module_name(p)) for p in modules(HOST)} - {None}
    assert on_disk <= set(MAY_IMPORT), "a host unit the layers do not place: %s" % (
        sorted(on_disk - set(MAY_IMPORT)),)


def test_every_host_import_follows_the_layers():
    g = host_graph()
    bad = {"%s -> %s" % (a, b): where for a, out in g.items() for b, where in out.items()
           if b not in MAY_IMPORT.get(a, set())}
    assert bad == {}


def test_the_link_is_only_the_connection():
    """The simulated boards (texelpad.sim: the virtual board, the emulated
    Pico) deploy into themselves; the link they connect through knows none
    of them and nothing of deploy."""
    g = host_graph()
    assert set(g["texelpad.link"]) <= {"texelpad.toolchain"}, g["texelpad.link"]


def test_the_root_package_imports_nothing_when_imported():
    """`from texelpad import __version__` (link, deploy, study, firmware)
    loads no layer: the root's own imports (connect, encode) are inside its
    functions."""
    tree = ast.parse((HOST / "__init__.py").read_text(encoding="utf-8"))
    assert [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))] == []


# --- cycles between modules, inside a package too (issue 33) -------------------------------
# The layer graph above sees packages; these are the modules: every import of a module
# (module level or in a function: a lazy import still makes the importer depend on it), in the
# device package and the host package. The root packages are left out: their lazy entry points
# (texelpad.connect, texel.render) import downwards on first use by design.
ALLOWED_CYCLES = {
    ("texel.gen.options", "texel.gen.plan", "texel.gen.plan_int"):
        "the texture options (min_cpmm, phase: docs/generator.md) build on the plans' arithmetic, "
        "and a plan applies them, importing options only when a texture sets one",
    ("texel.runtime.refresh_fast", "texel.runtime.refresh_viper"):
        "the fused refresh's Python side imports its viper core only where no C core has the "
        "refresh (refresh_fast._viper), and the viper module checks its compile-time copy of "
        "the W/S layout against refresh_fast's and hands its globals back at import",
}


def _module_cycles(root: Path) -> list[tuple[str, ...]]:
    mods = {_module_name(p): p for p in modules(root)}
    top = _module_name(root / "__init__.py")
    # (a module's own packages are no edge: a submodule always runs its package's __init__)
    graph = {n: {m for m in imports(p)
                 if m in mods and m not in (n, top) and not n.startswith(m + ".")}
             for n, p in mods.items() if n != top}
    return sorted(tuple(c) for c in cycles(graph))      # the layer graph's Tarjan, above


def test_no_import_cycles_between_modules_but_the_explained_ones():
    cycles = _module_cycles(DEVICE) + _module_cycles(HOST)
    assert cycles == sorted(ALLOWED_CYCLES), cycles
