"""Names that say what they hold (issue 23 item 6): a one-letter module alias
means the same module in every host module that uses it (P was texel's params
in one and the encoder's perception in another), and the device's runtime
state is a class whose attributes are declared where it is defined."""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HOST = ROOT / "host" / "texelpad"


def _aliases() -> dict[str, dict[str, list[str]]]:
    """{one-letter alias: {the module it names: [files]}} over the host package."""
    out: dict[str, dict[str, list[str]]] = {}
    for path in sorted(HOST.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                for a in node.names:
                    if a.asname and len(a.asname) == 1:
                        mod = a.name.rsplit(".", 1)[-1]
                        out.setdefault(a.asname, {}).setdefault(mod, []).append(
                            str(path.relative_to(ROOT)))
    return out


def test_a_one_letter_alias_names_one_module():
    clash = {k: v for k, v in _aliases().items() if len(v) > 1}
    assert clash == {}, "one alias, several modules: %s" % clash


def test_the_runtime_state_declares_its_attributes():
    """texel.app's runtime holder: every attribute app.py sets on it is
    declared in its class (no bare `class _Runtime: pass` filled in later)."""
    src = (ROOT / "device" / "texel" / "app.py").read_text()
    mod = ast.parse(src)
    cls = [n for n in mod.body if isinstance(n, ast.ClassDef) and n.name == "_Runtime"]
    assert cls, "texel.app._Runtime"
    declared = set()
    for n in ast.walk(cls[0]):
        if isinstance(n, ast.Attribute) and isinstance(n.ctx, ast.Store) \
                and isinstance(n.value, ast.Name) and n.value.id == "self":
            declared.add(n.attr)
        if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store):
            declared.add(n.id)
    used = set()
    for n in ast.walk(mod):
        if isinstance(n, ast.Attribute) and isinstance(n.ctx, ast.Store) \
                and isinstance(n.value, ast.Name) and n.value.id in ("rt", "_rt"):
            used.add(n.attr)
    assert used - declared == set(), "set on the runtime but not declared: %s" % (
        sorted(used - declared))
