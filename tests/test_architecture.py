"""The architecture, read from the source with ``ast`` (docs/architecture.md).

Layers import downward only: foundation -> params -> kinematics -> (calibration | cad) -> export
-> the package facade -> cli / interop -> __main__, counting function-level imports and
``importlib`` loads of a literal module name; no module cycle, no package cycle; no module
registers itself into another package's state when imported; the pure maths never imports a CAD
library; no module but topology.py types the hand's names or turns a 0-based index into a label.
"""

from __future__ import annotations

import ast
import functools
import shutil
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "phantom_cad"

#: modules every layer may import: pure data and formulas, imported by the params layer itself
FOUNDATION = {"phantom_cad.units", "phantom_cad.canon", "phantom_cad.errors", "phantom_cad.atomic",
              "phantom_cad.workers",
              "phantom_cad.kinematics.topology", "phantom_cad.kinematics.closed_form",
              "phantom_cad.kinematics.dimensions", "phantom_cad.kinematics.hand_params"}
#: package -> layer; packages on one layer must not import each other
LAYERS = {"params": 1, "kinematics": 2, "calibration": 3, "cad": 3, "sizing": 3, "postures": 3, "export": 4,
          "drive": 4, "": 5, "retargeting": 5, "cli": 6, "interop": 6, "__main__": 7}
CAD_LIBRARIES = {"build123d", "cadquery", "OCP", "manifold3d", "trimesh"}
#: importlib's functions that load a module by its name (the first argument)
IMPORTLIB_LOADERS = {"import_module", "find_spec"}


def module_name(path: Path, pkg: Path = PKG) -> str:
    parts = list(path.relative_to(pkg.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def is_package(path: Path) -> bool:
    return path.name == "__init__.py"


@functools.lru_cache(maxsize=None)
def parse(path: Path) -> ast.Module:
    """The module's syntax tree (each file read once per session; the probes' copies are other paths)."""
    return ast.parse(path.read_text(), str(path))


def _string_constants(tree: ast.Module) -> dict[str, str]:
    """Module-level names bound once to a string literal (``ASSEMBLY_MODULE = "phantom_cad..."``)."""
    out: dict[str, str] = {}
    for node in tree.body:
        if (isinstance(node, (ast.Assign, ast.AnnAssign)) and isinstance(node.value, ast.Constant)
                and isinstance(node.value.value, str)):
            for t in (node.targets if isinstance(node, ast.Assign) else [node.target]):
                if isinstance(t, ast.Name):
                    out[t.id] = node.value.value
    return out


def _literal_names(node: ast.AST, constants: dict[str, str]) -> list[str]:
    """The module names an importlib call's argument can be: a literal, a module-level string
    constant, or either side of ``a or b``."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, ast.Name) and node.id in constants:
        return [constants[node.id]]
    if isinstance(node, ast.BoolOp):
        return [n for v in node.values for n in _literal_names(v, constants)]
    return []


def _importlib_load(node: ast.Call) -> bool:
    f = node.func
    name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
    return name in IMPORTLIB_LOADERS and bool(node.args)


def imports(path: Path, modules: dict[str, Path] | None = None, pkg: Path = PKG) -> list[tuple[str, int]]:
    """Absolute names of every module ``path`` imports (any depth in the file), with line numbers:
    import statements, and importlib loads of a literal name (``importlib.import_module("x")``,
    ``importlib.util.find_spec("x")``; a module-level string constant counts as a literal).
    ``from X import y`` counts as an import of X.y when X.y is a module, else of X."""
    modules = MODULES if modules is None else modules
    me = module_name(path, pkg)
    base = me if is_package(path) else me.rpartition(".")[0]
    tree = parse(path)
    constants = _string_constants(tree)
    out = []
    for node in ast.walk(tree):
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
                out.append((sub if sub in modules else mod, node.lineno))
        elif isinstance(node, ast.Call) and _importlib_load(node):
            out += [(name, node.lineno) for name in _literal_names(node.args[0], constants)]
    return out


def package_modules(pkg: Path) -> dict[str, Path]:
    return {module_name(f, pkg): f for f in sorted(pkg.rglob("*.py"))}


FILES = sorted(PKG.rglob("*.py"))
MODULES = package_modules(PKG)


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


def downward_violations(modules: dict[str, Path], pkg: Path = PKG) -> list[str]:
    """Every upward or sideways import (statements and importlib loads) of ``modules``."""
    bad = []
    for mod, path in modules.items():
        for name, line in imports(path, modules, pkg):
            if name.split(".")[0] != "phantom_cad" or name == mod:
                continue
            target = name if name in modules else name.rpartition(".")[0]
            same_package = package(target) == package(mod)
            if mod in FOUNDATION and target not in FOUNDATION:
                bad.append(f"{path.relative_to(pkg.parent)}:{line}: foundation module {mod} imports {target}")
            elif layer(target) > layer(mod) or (layer(target) == layer(mod) and not same_package
                                                 and target not in FOUNDATION):
                bad.append(f"{path.relative_to(pkg.parent)}:{line}: {mod} (layer {layer(mod)}) imports "
                           f"{target} (layer {layer(target)})")
    return bad


def test_imports_go_downward_only():
    bad = downward_violations(MODULES)
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


def probe_copy(tmp_path: Path, files: dict[str, str]) -> tuple[Path, dict[str, Path]]:
    """A copy of the package under ``tmp_path`` with made-up ``files`` (path in the package -> text)
    added: the probes never write into the package itself."""
    pkg = tmp_path / "phantom_cad"
    shutil.copytree(PKG, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    for rel, text in files.items():
        (pkg / rel).write_text(text)
    return pkg, package_modules(pkg)


def test_architecture_test_sees_function_level_imports(tmp_path):
    # the reader must see an import inside a function body: a known answer on a made-up file
    pkg, modules = probe_copy(tmp_path, {"calibration/_probe.py": "def f():\n    from ..export import manifest\n"})
    probe = pkg / "calibration" / "_probe.py"
    assert ("phantom_cad.export.manifest", 2) in imports(probe, modules, pkg)
    assert any("_probe.py:2: phantom_cad.calibration._probe (layer 3) imports phantom_cad.export.manifest" in b
               for b in downward_violations(modules, pkg))


def test_architecture_test_sees_importlib_loads(tmp_path):
    # a literal name given to importlib is an import like any other; a name computed at run time is not
    text = ("import importlib\nimport importlib.util\nLATER = 'phantom_cad.export.bom'\n"
            "def f(name):\n    importlib.import_module('phantom_cad.cli')\n"
            "    importlib.util.find_spec('phantom_cad.export.manifest')\n"
            "    importlib.import_module(name or LATER)\n    importlib.import_module(name)\n")
    pkg, modules = probe_copy(tmp_path, {"kinematics/_probe.py": text})
    found = [(n, line) for n, line in imports(pkg / "kinematics" / "_probe.py", modules, pkg)
             if n.startswith("phantom_cad")]
    assert found == [("phantom_cad.cli", 5), ("phantom_cad.export.manifest", 6), ("phantom_cad.export.bom", 7)]
    bad = downward_violations(modules, pkg)
    assert sum("kinematics._probe (layer 2) imports" in b for b in bad) == 3


def test_the_assembly_interface_is_seen_as_an_import():
    # export/interface.py loads the parts module by name (the tests swap in a stand-in): export -> cad
    assert ("phantom_cad.cad.assembly", 22) in imports(MODULES["phantom_cad.export.interface"])


# -- import-time registration ------------------------------------------------------

#: methods that change the object they are called on
MUTATORS = {"append", "extend", "insert", "update", "add", "setdefault", "pop", "popitem", "remove", "discard",
            "clear", "__setitem__", "__delitem__"}


def _module_level(tree: ast.Module):
    """The nodes that run when the module is imported: everything but function bodies (a def's
    decorators and defaults run; a class body runs)."""
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        yield node
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            todo += node.decorator_list + node.args.defaults + [d for d in node.args.kw_defaults if d]
        elif not isinstance(node, ast.Lambda):
            todo += list(ast.iter_child_nodes(node))


def _bindings(path: Path, modules: dict[str, Path], pkg: Path) -> dict[str, tuple[str, str | None]]:
    """Names the module binds by importing from the package: name -> (module, None) for a module,
    (module, attribute) for an object of a module."""
    me = module_name(path, pkg)
    base = me if is_package(path) else me.rpartition(".")[0]
    out: dict[str, tuple[str, str | None]] = {}
    for node in ast.walk(parse(path)):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name in modules:
                    out[a.asname or a.name.split(".")[0]] = (a.name if a.asname else a.name.split(".")[0], None)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = base.split(".")
                mod = ".".join(anchor[:len(anchor) - (node.level - 1)] + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            for a in node.names:
                sub = f"{mod}.{a.name}"
                if sub in modules:
                    out[a.asname or a.name] = (sub, None)
                elif mod in modules:
                    out[a.asname or a.name] = (mod, a.name)
    return out


def _root(node: ast.AST) -> ast.AST:
    while isinstance(node, (ast.Attribute, ast.Subscript)):
        node = node.value
    return node


def _mutating_functions(path: Path) -> set[str]:
    """Top-level functions of a module that change its module-level state: a method of MUTATORS
    called on, or an item or attribute assigned to, a module-level name, or a ``global``."""
    tree = parse(path)
    state = {t.id for node in tree.body if isinstance(node, (ast.Assign, ast.AnnAssign))
             for t in (node.targets if isinstance(node, ast.Assign) else [node.target]) if isinstance(t, ast.Name)}
    out = set()
    for fn in tree.body:
        if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        for node in ast.walk(fn):
            if isinstance(node, ast.Global) or (
                    isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in MUTATORS
                    and isinstance(_root(node.func.value), ast.Name) and _root(node.func.value).id in state) or (
                    isinstance(node, (ast.Assign, ast.AugAssign, ast.Delete))
                    and any(isinstance(t, (ast.Subscript, ast.Attribute)) and isinstance(_root(t), ast.Name)
                            and _root(t).id in state
                            for t in (node.targets if isinstance(node, (ast.Assign, ast.Delete)) else [node.target]))):
                out.add(fn.name)
                break
    return out


def registrations(modules: dict[str, Path], pkg: Path = PKG) -> list[tuple[str, str, str]]:
    """(module, the other package's module whose state it changes, where) for every statement that
    runs at import and changes another package's module state: assigns into or calls a MUTATORS
    method on a name imported from it, or calls a function of it that changes its own state."""
    mutating = {m: _mutating_functions(p) for m, p in modules.items()}
    out = []
    for mod, path in modules.items():
        names = _bindings(path, modules, pkg)

        def foreign(node):
            r = _root(node)
            if isinstance(r, ast.Name) and r.id in names and package(names[r.id][0]) != package(mod):
                return names[r.id]
            return None

        for node in _module_level(parse(path)):
            hit = None
            if isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign, ast.Delete)):
                targets = node.targets if isinstance(node, (ast.Assign, ast.Delete)) else [node.target]
                hit = next((foreign(t) for t in targets if isinstance(t, (ast.Attribute, ast.Subscript))
                            and foreign(t)), None)
            elif isinstance(node, ast.Call):
                f = node.func
                if isinstance(f, ast.Attribute) and f.attr in MUTATORS:
                    hit = foreign(f.value)
                else:
                    target = foreign(f)
                    fname = (target[1] if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute)
                             and isinstance(f.value, ast.Name) else None) if target else None
                    if fname in mutating.get(target[0] if target else "", ()):
                        hit = target
            if hit:
                out.append((mod, hit[0], f"{path.relative_to(pkg.parent)}:{node.lineno}"))
    return out


def test_no_import_time_registration_across_packages():
    bad = [f"{where}: importing {mod} changes {target}'s state"
           for mod, target, where in registrations(MODULES)]
    assert not bad, "\n".join(bad)


def test_architecture_test_sees_registration(tmp_path):
    # known answers on made-up modules: direct changes and a call of a registering function at import
    # are found; the same inside a function (run when called, not when imported) is not
    hooks = "HOOKS = []\nVERSION = 1\ndef register(f):\n    HOOKS.append(f)\ndef count():\n    return len(HOOKS)\n"
    text = ("from ..params import _hooks\nfrom ..params._hooks import register, count, HOOKS\n"
            "_hooks.HOOKS.append(print)\nHOOKS[:] = []\nregister(print)\n"
            "_hooks.register(print)\n_hooks.VERSION = 2\ncount()\n"
            "def later():\n    register(print)\n    HOOKS.append(print)\n")
    pkg, modules = probe_copy(tmp_path, {"params/_hooks.py": hooks, "kinematics/_probe.py": text})
    found = sorted(int(where.rpartition(":")[2]) for mod, target, where in registrations(modules, pkg)
                   if mod == "phantom_cad.kinematics._probe" and target == "phantom_cad.params._hooks")
    assert found == [3, 4, 5, 6, 7]


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
        for node in ast.walk(parse(path)):
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
