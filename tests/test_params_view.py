"""The typed view of the parameters, read from the source with ``ast`` (no CAD import).

The kinematics, the CAD and the export read the records of ``kinematics/hand_params.py``: every
argument named ``params`` of a function there is annotated ``HandParams``, and every attribute
chain read on an argument annotated with one of the records (``params.palm.finger_pitch``,
``chain.radii``) resolves, link by link, to a field, property or method of the record, following
the dataclasses' type hints; so does every chain read on ``self.params`` in a method (the parts,
the model: the hand they belong to). A chain stops at a type that is not a record, at a
subscript, and at a call whose method does not return a record. The checker's own checks run on
made-up sources.
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import inspect
import textwrap
import types
import typing
from pathlib import Path

import pytest

from phantom_cad.kinematics import hand_params

PKG = Path(__file__).resolve().parents[1] / "phantom_cad"
#: the packages that read the parsed hand
READERS = ("kinematics", "cad", "export")

RECORDS: dict[str, type] = {name: obj for name, obj in vars(hand_params).items()
                            if isinstance(obj, type) and dataclasses.is_dataclass(obj)
                            and obj.__module__ == hand_params.__name__}
FUNCTIONS = (ast.FunctionDef, ast.AsyncFunctionDef)


def annotated_records(node: ast.expr | None) -> tuple[type, ...]:
    """The records an annotation names: ``Finger``, ``hand_params.Finger``, ``Finger | Thumb``,
    ``"Finger"``; ``| None`` adds none. Empty when any member is not a record (``HandParams |
    Mapping``: the argument is not read as a record alone) or there is no annotation."""
    if node is None:
        return ()
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return annotated_records(ast.parse(node.value, mode="eval").body)
    members: list[ast.expr] = []

    def split(n: ast.expr) -> None:
        if isinstance(n, ast.BinOp) and isinstance(n.op, ast.BitOr):
            split(n.left)
            split(n.right)
        else:
            members.append(n)

    split(node)
    out: list[type] = []
    for m in members:
        if isinstance(m, ast.Constant) and m.value is None:
            continue
        name = m.id if isinstance(m, ast.Name) else m.attr if isinstance(m, ast.Attribute) else None
        if name not in RECORDS:
            return ()
        out.append(RECORDS[name])
    return tuple(out)


def hinted_records(hint) -> tuple[type, ...]:
    """The records a type hint is (``Finger``, ``Finger | Thumb``, ``Optional[Finger]``); empty
    for anything else (``float``, ``Mapping[str, Finger]``, ``tuple[ChainParams, ...]``)."""
    if isinstance(hint, type) and hint in RECORDS.values():
        return (hint,)
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        if args and all(isinstance(a, type) and a in RECORDS.values() for a in args):
            return tuple(args)
    return ()


class _Self:
    """The ``self`` of a method: of its attributes only ``params`` is followed, as the hand (a
    part's, a model's, an exporter context's)."""


SELF = (_Self,)
_MISSING = object()


@functools.lru_cache(maxsize=None)
def member(cls: type, attr: str) -> tuple[str, object] | None:
    """What ``attr`` is on the record ``cls``: ("field" | "property" | "method" | "attribute",
    its type hint or None), or None when the record has no such member."""
    fields = {f.name for f in dataclasses.fields(cls)}
    if attr in fields:
        return "field", typing.get_type_hints(cls)[attr]
    obj = inspect.getattr_static(cls, attr, _MISSING)
    if obj is _MISSING:
        return None
    if isinstance(obj, property):
        return "property", typing.get_type_hints(obj.fget).get("return")
    if isinstance(obj, functools.cached_property):
        return "property", typing.get_type_hints(obj.func).get("return")
    if inspect.isfunction(obj):
        return "method", typing.get_type_hints(obj).get("return")
    return "attribute", None


@dataclasses.dataclass
class Findings:
    unannotated: list[str] = dataclasses.field(default_factory=list)
    unknown: list[str] = dataclasses.field(default_factory=list)
    #: attribute reads resolved on a record, link by link
    resolved: int = 0


def _arguments(args: ast.arguments) -> list[ast.arg]:
    return [*args.posonlyargs, *args.args, *([args.vararg] if args.vararg else []), *args.kwonlyargs,
            *([args.kwarg] if args.kwarg else [])]


def check_source(text: str, where: str) -> Findings:
    """The offenders of one module's source (``where`` names it in the findings)."""
    tree = ast.parse(text, where)
    parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
    found = Findings()

    def follow(name: ast.Name, records: tuple[type, ...], function: str) -> None:
        node: ast.expr = name
        chain = [name.id]
        if records == SELF:         # a method's ``self``: its ``params`` is the hand
            parent = parents.get(node)
            if not (isinstance(parent, ast.Attribute) and parent.value is node and parent.attr == "params"):
                return
            chain.append("params")
            node, records = parent, (hand_params.HandParams,)
        while records:
            parent = parents.get(node)
            if not (isinstance(parent, ast.Attribute) and parent.value is node):
                return
            chain.append(parent.attr)
            hits = [m for m in (member(c, parent.attr) for c in records) if m is not None]
            # a union (``Finger | Thumb``) must have it on every member: the checker cannot see
            # which one the code holds
            if len(hits) < len(records):
                found.unknown.append(
                    f"{where}:{parent.lineno} {function}: {'.'.join(chain)}: "
                    f"{' | '.join(c.__name__ for c in records)} has no field, property or method "
                    f"'{parent.attr}'")
                return
            found.resolved += 1
            node = parent
            kinds = {k for k, _ in hits}
            if kinds == {"method"}:
                call = parents.get(node)
                if not (isinstance(call, ast.Call) and call.func is node):
                    return
                node = call
                chain[-1] += "()"
            elif kinds - {"field", "property"}:
                return
            records = tuple(dict.fromkeys(c for _, hint in hits for c in hinted_records(hint)))

    def visit(node: ast.AST, env: dict[str, tuple[type, ...]], function: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (*FUNCTIONS, ast.Lambda)):
                # decorators, defaults and annotations belong to the enclosing scope
                outer = [*getattr(child, "decorator_list", []), *child.args.defaults,
                         *[d for d in child.args.kw_defaults if d is not None]]
                for n in outer:
                    visit_expr(n, env, function)
                inner = dict(env)
                name = getattr(child, "name", function)
                for arg in _arguments(child.args):
                    records = annotated_records(arg.annotation)
                    if (arg.arg == "params" and isinstance(child, FUNCTIONS)
                            and hand_params.HandParams not in records):
                        found.unannotated.append(f"{where}:{child.lineno} {name}")
                    if records:
                        inner[arg.arg] = records
                    else:
                        inner.pop(arg.arg, None)
                if isinstance(node, ast.ClassDef) and isinstance(child, FUNCTIONS) and child.args.args \
                        and child.args.args[0].arg == "self":
                    inner["self"] = SELF
                body = child.body if isinstance(child, FUNCTIONS) else [child.body]
                for b in body:
                    visit_expr(b, inner, name)
            else:
                visit_expr(child, env, function)

    def visit_expr(node: ast.AST, env: dict[str, tuple[type, ...]], function: str) -> None:
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load) and node.id in env:
            follow(node, env[node.id], function)
        if isinstance(node, (*FUNCTIONS, ast.Lambda)):
            visit(ast.Module(body=[node], type_ignores=[]), env, function)
        else:
            visit(node, env, function)

    visit(tree, {}, "<module>")
    return found


def reader_files() -> list[Path]:
    return [p for pkg in READERS for p in sorted((PKG / pkg).rglob("*.py"))]


@functools.lru_cache(maxsize=None)
def findings() -> Findings:
    out = Findings()
    for path in reader_files():
        f = check_source(path.read_text(), str(path.relative_to(PKG.parent)))
        out.unannotated += f.unannotated
        out.unknown += f.unknown
        out.resolved += f.resolved
    return out


def test_the_records_are_the_params_layers():
    """``phantom_cad.params`` hands out the very records the readers are typed with."""
    from phantom_cad import params
    from phantom_cad.params import schema

    for name, cls in RECORDS.items():
        assert getattr(schema, name) is cls
    assert params.HandParams is hand_params.HandParams


def test_every_params_argument_is_annotated_handparams():
    bad = findings().unannotated
    assert not bad, "arguments named params not annotated HandParams:\n" + "\n".join(bad)


def test_every_attribute_read_on_a_record_resolves():
    bad = findings().unknown
    assert not bad, "attributes the records do not have:\n" + "\n".join(bad)


def test_the_readers_use_the_view():
    """The checks above see something: the readers annotate arguments with the records and read
    through them (a checker that found no annotated argument would pass on anything)."""
    annotated = sum(1 for path in reader_files() for node in ast.walk(ast.parse(path.read_text()))
                    if isinstance(node, ast.arg) and annotated_records(node.annotation))
    assert annotated >= 100
    assert findings().resolved >= 200


# -- the checker's own checks, on made-up sources ---------------------------------------------

def check(text: str) -> Findings:
    return check_source(textwrap.dedent(text), "probe.py")


def test_checker_reports_an_unknown_field():
    f = check("""
        from phantom_cad.kinematics.hand_params import HandParams

        def width(params: HandParams) -> float:
            return params.palm.no_such_field
        """)
    assert f.unknown == ["probe.py:5 width: params.palm.no_such_field: Palm has no field, property "
                         "or method 'no_such_field'"]
    assert f.unannotated == []


def test_checker_reports_an_unannotated_params():
    f = check("""
        def width(params, other: int):
            return params.palm.no_such_field

        class Part:
            def build(self, *, params=None):
                return params
        """)
    assert f.unannotated == ["probe.py:2 width", "probe.py:6 build"]
    assert f.unknown == []   # an unannotated argument has no type to check against


def test_checker_refuses_params_annotated_otherwise():
    f = check("""
        from typing import Any, Mapping

        def a(params: Any): ...
        def b(params: "HandParams | Mapping"): ...
        def c(params: HandParams | None = None): ...
        def d(params: "HandParams"): ...
        """)
    assert f.unannotated == ["probe.py:4 a", "probe.py:5 b"]


@pytest.mark.parametrize("read, bad", [
    ("params.thumb.chain.guide.d1", None),
    ("params.thumb.chain.guide.L0", None),              # a property
    ("params.thumb.chain.guide.d3", "params.thumb.chain.guide.d3"),
    ("params.chains[0].radius", None),                  # stops at a subscript
    ("params.fingers['index'].no_such", None),
    ("params.digit('index').chain.radii", None),        # the method's return type: Finger | Thumb
    ("params.digit('index').middle", "params.digit().middle"),   # a Finger's, not a Thumb's
    ("params.digest.hex", None),                        # a cached property: str, not a record
    ("params.digit.chain", None),                       # a method not called: the chain stops
    ("chain.spec.digit", None),                         # topology.Chain is not a record
    ("chain.radius", "chain.radius"),
])
def test_checker_follows_chains_link_by_link(read, bad):
    f = check(f"""
        from phantom_cad.kinematics.hand_params import ChainParams, HandParams

        def reader(params: HandParams, chain: ChainParams):
            return {read}
        """)
    assert [u.split(": ")[1] for u in f.unknown] == ([bad] if bad else [])


def test_checker_follows_scopes():
    """A nested function sees the enclosing argument; an argument of its own (or a lambda's)
    shadows it; a default is read in the enclosing scope."""
    f = check("""
        def outer(params: HandParams, hw: Hardware | None = None):
            def inner(x):
                return params.palm.nope1 + hw.nope2
            def shadow(params):
                return params.palm.fine_untyped
            g = lambda hw: hw.fine_untyped
            def default(x=params.nope3):
                return x
            return inner, shadow, g, default
        """)
    assert [u.split(": ")[1] for u in f.unknown] == ["params.palm.nope1", "hw.nope2", "params.nope3"]
    assert f.unannotated == ["probe.py:5 shadow"]


def test_checker_follows_self_params_in_methods():
    """In a method, ``self.params`` is the hand; ``self``'s other attributes and a function's own
    ``self`` argument outside a class are not followed."""
    f = check("""
        class Phalanx:
            def width(self):
                return self.params.palm.nope1 + self.params.palm.finger_pitch + self.other.nope

            @staticmethod
            def static(x):
                return x.params.nope

        def free(self):
            return self.params.nope
        """)
    assert [u.split(": ")[1] for u in f.unknown] == ["self.params.palm.nope1"]
