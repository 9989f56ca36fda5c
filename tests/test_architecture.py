"""The architecture, read from the source with ``ast`` (docs/architecture.md).

Layers import downward only: foundation -> params -> kinematics -> (calibration | cad) -> export
-> the package facade -> cli / interop -> __main__, counting function-level imports; no module cycle, no
package cycle; the pure maths never imports a CAD library; no module but topology.py types the
hand's names or turns a 0-based index into a label.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "phantom_cad"

#: modules every layer may import: pure data and formulas, imported by the params layer itself
FOUNDATION = {"phantom_cad.units", "phantom_cad.canon", "phantom_cad.errors", "phantom_cad.atomic",
              "phantom_cad.workers",
              "phantom_cad.kinematics.topology", "phantom_cad.kinematics.closed_form",
              "phantom_cad.kinematics.dimensions"}
#: package -> layer; packages on one layer must not import each other
LAYERS = {"params": 1, "kinematics": 2, "calibration": 3, "cad": 3, "export": 4, "": 5,
          "cli": 6, "interop": 6, "__main__": 7}
CAD_LIBRARIES = {"build123d", "cadquery", "OCP", "manifold3d", "trimesh"}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def is_package(path: Path) -> bool:
    return path.name == "__init__.py"


def imports(path: Path) -> list[tuple[str, int]]:
    """Absolute names of every module ``path`` imports (any depth in the file), with line numbers.
    ``from X import y`` counts as an import of X.y when X.y is a module, else of X."""
    me = module_name(path)
    base = me if is_package(path) else me.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = base.split(".")
                anchor = anchor[:len(anchor) - (node.level - 1)]
                mod = ".".join(anchor + ([node.module] if node.module else []))
            else:
                mod = node.module
            for a in node.names:
                sub = f"{mod}.{a.name}"
                out.append((sub if sub in MODULES else mod, node.lineno))
    return out


FILES = sorted(PKG.rglob("*.py"))
MODULES = {module_name(f): f for f in FILES}


def package(mod: str) -> str:
    parts = mod.split(".")
    return parts[1] if len(parts) > 1 else ""


def layer(mod: str) -> int:
    return 0 if mod in FOUNDATION else LAYERS[package(mod)]


def graph() -> dict[str, set[str]]:
    g = {m: set() for m in MODULES}
    for mod, path in MODULES.items():
        for name, _ in imports(path):
            if name.split(".")[0] == "phantom_cad" and name != mod:
                g[mod].add(name if name in MODULES else name.rpartition(".")[0])
    return g


def test_every_package_has_a_layer():
    assert {package(m) for m in MODULES if m not in FOUNDATION} <= set(LAYERS)


def test_imports_go_downward_only():
    bad = []
    for mod, path in MODULES.items():
        for name, line in imports(path):
            if name.split(".")[0] != "phantom_cad" or name == mod:
                continue
            target = name if name in MODULES else name.rpartition(".")[0]
            same_package = package(target) == package(mod)
            if mod in FOUNDATION and target not in FOUNDATION:
                bad.append(f"{path.relative_to(PKG.parent)}:{line}: foundation module {mod} imports {target}")
            elif layer(target) > layer(mod) or (layer(target) == layer(mod) and not same_package
                                                 and target not in FOUNDATION):
                bad.append(f"{path.relative_to(PKG.parent)}:{line}: {mod} (layer {layer(mod)}) imports "
                           f"{target} (layer {layer(target)})")
    assert not bad, "upward or sideways imports:\n" + "\n".join(bad)


def _cycle(g: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(g.get(n, ())):
            if state.get(m) == 1:
                return stack[stack.index(m):] + [m]
            if m not in state:
                found = visit(m)
                if found:
                    return found
        stack.pop()
        state[n] = 2
        return None

    for n in sorted(g):
        if n not in state:
            found = visit(n)
            if found:
                return found
    return None


def test_no_module_cycle():
    g = graph()
    # a package's __init__ importing its own submodules is not a cycle of the design
    for m in g:
        g[m] = {t for t in g[m] if not (t.startswith(m + ".") and MODULES[m].name == "__init__.py")}
    cycle = _cycle(g)
    assert cycle is None, " -> ".join(cycle)


def test_no_package_cycle():
    pg: dict[str, set[str]] = {}
    for mod, targets in graph().items():
        for t in targets:
            a, b = package(mod), package(t)
            if a != b and t not in FOUNDATION and a != "":
                pg.setdefault(a, set()).add(b)
    cycle = _cycle(pg)
    assert cycle is None, " <-> ".join(cycle)


@pytest.mark.parametrize("pkg", ["params", "kinematics", "calibration"])
def test_pure_maths_never_imports_cad(pkg):
    bad = [f"{p.relative_to(PKG.parent)}:{line}: {name}"
           for p in sorted((PKG / pkg).rglob("*.py")) for name, line in imports(p)
           if name.split(".")[0] in CAD_LIBRARIES]
    assert not bad


def test_architecture_test_sees_function_level_imports(tmp_path):
    # the reader must see an import inside a function body: a known answer on a made-up file
    probe = PKG / "calibration" / "_probe_for_test.py"
    probe.write_text("def f():\n    from ..export import manifest\n")
    try:
        MODULES[module_name(probe)] = probe
        assert ("phantom_cad.export.manifest", 2) in imports(probe)
    finally:
        MODULES.pop(module_name(probe), None)
        probe.unlink()


# -- one topology ------------------------------------------------------------------

#: names only topology.py may list: joint keys, digits, segments
TOPOLOGY_WORDS = {"mcp", "pip", "dip", "mp", "ip", "cmc", "thumb", "index", "middle", "ring", "pinky",
                  "metacarpal", "proximal", "distal", "base", "cmc_base"}


def _label_arithmetic(node: ast.JoinedStr) -> bool:
    """f"u{j + 1}", f"q{i + 1}", f"servo_pulley_{k + 1}": a label typed from a 0-based index."""
    for a, b in zip(node.values, node.values[1:]):
        if (isinstance(a, ast.Constant) and isinstance(a.value, str) and a.value.endswith(("u", "q", "_"))
                and isinstance(b, ast.FormattedValue) and isinstance(b.value, ast.BinOp)
                and isinstance(b.value.op, ast.Add) and isinstance(b.value.right, ast.Constant)
                and b.value.right.value in (1, 2)):
            return True
    return False


def test_no_name_list_or_index_arithmetic_outside_topology():
    bad = []
    for path in FILES:
        if path.name == "topology.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.Tuple, ast.List)) and len(node.elts) >= 2 and all(
                    isinstance(e, ast.Constant) and e.value in TOPOLOGY_WORDS for e in node.elts):
                bad.append(f"{path.relative_to(PKG.parent)}:{node.lineno}: name list "
                           f"{[e.value for e in node.elts]}")
            if isinstance(node, ast.JoinedStr) and _label_arithmetic(node):
                bad.append(f"{path.relative_to(PKG.parent)}:{node.lineno}: label from index arithmetic")
            if (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add)
                    and isinstance(node.left, ast.Call) and getattr(node.left.func, "attr", "") == "index"
                    and isinstance(node.right, ast.Constant) and isinstance(node.right.value, int)):
                bad.append(f"{path.relative_to(PKG.parent)}:{node.lineno}: index arithmetic on .index()")
    assert not bad, "\n".join(bad)
