"""STEP, STL and BREP writers with deterministic output, and the mesh checks (the solid's
own validity is checked once, by ``phantom_cad.cad.verify``).

Everything that touches OCP/build123d imports it inside the function; the pure-mesh
helpers (binary STL writer/reader, mesh checks) use numpy, trimesh and manifold3d only.

Determinism
-----------
* STEP: build123d's ``export_step`` writes the current time into ``FILE_NAME`` unless a
  timestamp is given; we always pass :func:`step_timestamp` (``SOURCE_DATE_EPOCH`` when
  set, else the Unix epoch), so the same shape gives the same bytes.
* STL: written here from the BRepMesh triangulation as *binary* STL with a fixed
  80-byte header naming the part; no timestamps, float32 little endian.
"""

from __future__ import annotations

import io
import os
import re
import struct
from datetime import datetime, timezone

import numpy as np

from ..cad.verify import CheckError  # noqa: F401  (raised by check_mesh; the one check error)

#: angular deflection of the tessellation (rad, 11.5 deg: a CAD exporter's "fine" is 5-15 deg); the
#: linear one, params.print.stl_tolerance (0.02 mm), bounds every chord's distance to the surface.
#: At 0.1 rad the angle, not the chord, set the facets of every curve of radius under 16 mm (a
#: 2 mm pilot hole got 63 facets where 0.02 mm needs 16); at 0.2 rad, of radius under 4 mm (32).
#: The default hand's parts: 274,188 triangles at 0.1 rad, 116,168 at 0.2; every step after the
#: tessellation works on the lighter meshes (docs/performance.md)
ANGULAR_TOLERANCE_RAD = 0.2


def step_timestamp() -> str:
    """The timestamp written into STEP headers: ``SOURCE_DATE_EPOCH`` (reproducible-builds
    convention) when set, else 1970-01-01T00:00:00."""
    epoch = int(os.environ.get("SOURCE_DATE_EPOCH", "0") or 0)
    return datetime.fromtimestamp(epoch, tz=timezone.utc).strftime("%Y-%m-%dT%H:%M:%S")


# ---------------------------------------------------------------------------
# OCP side (lazy imports)

def step_bytes(shape, label: str | None = None, color=None) -> bytes:
    """STEP AP214 of one shape (or assembly compound) with a fixed header timestamp."""
    from build123d import Color, export_step

    if label is not None:
        shape.label = label
    if color is not None:
        shape.color = Color(*color)
    buf = io.BytesIO()
    export_step(shape, buf, timestamp=step_timestamp())
    return canonicalize_step(buf.getvalue())


_ENTITY = re.compile(rb"#(\d+)\s*=\s*((?:[^;']|'[^']*')*);")
#: an assembly's occurrence: OCCT numbers their ids from a counter that lives as long as the
#: process, so the same assembly written twice in one process gets other ids (and other line breaks)
_NAUO = re.compile(rb"NEXT_ASSEMBLY_USAGE_OCCURRENCE\s*\((?:[^;']|'[^']*')*\);")
_NAUO_ID = re.compile(rb"(NEXT_ASSEMBLY_USAGE_OCCURRENCE\s*\(\s*')\d+(')")
_LINE_BREAK = re.compile(rb"\r?\n[ \t]*")
_REF = re.compile(rb"#(\d+)")


def _split_entities(data: bytes):
    """(prefix, [(id, body)], suffix) of a STEP file's DATA section; body excludes ';'.
    Quoted strings may contain ';' or '#'."""
    start = data.index(b"DATA;") + len(b"DATA;")
    end = data.rindex(b"ENDSEC;")
    entities = [(int(m.group(1)), m.group(2)) for m in _ENTITY.finditer(data, start, end)]
    return data[:start], entities, data[end:]


def _refs(body: bytes) -> list[int]:
    # references outside quoted strings
    out, in_str = [], False
    for part in body.split(b"'"):
        if not in_str:
            out += [int(x) for x in _REF.findall(part)]
        in_str = not in_str
    return out


_BLOCK = b"MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION"
_ENTITY_START = re.compile(rb"#\d+\s*=\s*")


def _split_presentation(data: bytes):
    """(prefix through the DATA section's geometry, [(id, body)] of the presentation block, suffix),
    parsing only the block: None where the block's start is not found as an entity's or the
    geometry before it refers to (or numbers) an entity at or past the block's first, the cases
    :func:`canonicalize_step`'s whole-file parse handles."""
    at = data.find(_BLOCK)
    if at < 0:
        return None
    line = data.rfind(b"\n", 0, at) + 1
    if _ENTITY_START.fullmatch(data, line, at) is None:
        return None
    start, end = data.index(b"DATA;") + len(b"DATA;"), data.rindex(b"ENDSEC;")
    tail = [(int(m.group(1)), m.group(2)) for m in _ENTITY.finditer(data, line, end)]
    if not tail:
        return None
    head_numbers = _REF.findall(data, start, line)
    if head_numbers and max(map(int, head_numbers)) >= min(eid for eid, _ in tail):
        return None
    return data[:line], tail, data[end:]


def renumber_occurrences(data: bytes) -> bytes:
    """The STEP text with its NEXT_ASSEMBLY_USAGE_OCCURRENCE ids ('3', '4', ... from OCCT's
    process-wide counter: a part written after others in the same worker process got higher ones)
    renumbered '1', '2', ... in the order they appear, each such entity on one line (OCCT breaks
    its long lines where the id's width puts the break). Only the id string and the line breaks
    outside quoted strings change (a STEP reader ignores line breaks; the entities refer to an
    occurrence by its entity number, never by its id)."""
    n = 0

    def one(m):
        nonlocal n
        n += 1
        parts = m.group(0).split(b"'")
        parts[::2] = [_LINE_BREAK.sub(b"", p) for p in parts[::2]]        # outside quotes
        return _NAUO_ID.sub(lambda k: k.group(1) + str(n).encode() + k.group(2), b"'".join(parts), count=1)

    return _NAUO.sub(one, data)


def canonicalize_step(data: bytes) -> bytes:
    """Renumber the presentation block at the end of an OCCT STEP file canonically.

    OCCT writes the colour/style entities (from the first
    MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION to the end) in the iteration
    order of hash maps keyed by shape pointers, which changes from run to run for
    assemblies. Those entities are renumbered here in a depth-first order from their
    roots, the roots sorted by a structural hash, so the same model gives the same bytes.
    Entity contents are unchanged but for one thing: the ids of the assembly occurrences
    (NEXT_ASSEMBLY_USAGE_OCCURRENCE), which OCCT counts per process, are renumbered 1, 2, ... in
    the order the file writes them (:func:`renumber_occurrences`). The file is otherwise returned
    as is if it has no presentation block."""
    import hashlib

    data = renumber_occurrences(data)
    if _BLOCK not in data:
        return data
    # the block alone where the geometry before it is written as it is (renumbering nothing of
    # it: its 10^5 entities parsed took most of this function's time); else the whole file
    fast = _split_presentation(data)
    if fast is not None:
        prefix, tail, suffix = fast
        entities, first = [], 0
    else:
        try:
            prefix, entities, suffix = _split_entities(data)
        except ValueError:
            return data
        first = next((k for k, (_, body) in enumerate(entities) if body.startswith(_BLOCK)), None)
        if first is None:
            return data
        tail = entities[first:]
    tail_ids = [eid for eid, _ in tail]
    body_of = dict(tail)
    if len(body_of) != len(tail) or min(tail_ids) < max(eid for eid, _ in entities[:first] or [(0, b"")]):
        return data
    children = {eid: [r for r in _refs(body) if r in body_of] for eid, body in tail}
    digest: dict[int, bytes] = {}
    visiting: set[int] = set()

    def h(eid: int) -> bytes:
        if eid in digest:
            return digest[eid]
        if eid in visiting:
            raise ValueError("cycle")
        visiting.add(eid)
        text = _REF.sub(lambda m: (b"@" + h(int(m.group(1))).hex().encode()) if int(m.group(1)) in body_of
                        else m.group(0), body_of[eid])
        visiting.discard(eid)
        digest[eid] = hashlib.sha256(text).digest()
        return digest[eid]

    try:
        for eid in tail_ids:
            h(eid)
    except (ValueError, RecursionError):
        return data
    referenced = {c for eid in tail_ids for c in children[eid]}
    roots = sorted((eid for eid in tail_ids if eid not in referenced), key=lambda e: (digest[e], e))
    order: list[int] = []
    seen: set[int] = set()

    def visit(eid: int) -> None:
        stack = [eid]
        while stack:
            e = stack.pop()
            if e in seen:
                continue
            seen.add(e)
            order.append(e)
            stack.extend(reversed(children[e]))

    for r in roots:
        visit(r)
    if len(order) != len(tail_ids):
        return data
    base = min(tail_ids)
    new_id = {old: base + k for k, old in enumerate(order)}

    def renum(body: bytes) -> bytes:
        parts = body.split(b"'")
        for k in range(0, len(parts), 2):  # outside quotes
            parts[k] = _REF.sub(lambda m: b"#%d" % new_id.get(int(m.group(1)), int(m.group(1))), parts[k])
        return b"'".join(parts)

    head = entities[:first]
    out = [prefix] if fast is not None else [prefix, b"\n"]
    # the geometry before the block refers to none of it, as a rule: then it is written unchanged
    head_refs = [int(r) for _, body in head for r in _REF.findall(body)]
    keep = not head_refs or max(head_refs) < base
    for eid, body in head:
        out.append(b"#%d = %s;\n" % (eid, body if keep else renum(body)))
    for old in order:
        out.append(b"#%d = %s;\n" % (new_id[old], renum(body_of[old])))
    out.append(suffix)
    return b"".join(out)


def step_volume(path: str | os.PathLike) -> float:
    """Re-import a STEP file with build123d and return its volume (mm^3)."""
    from build123d import import_step

    return float(import_step(str(path)).volume)


def brep_bytes(shape) -> bytes:
    from build123d import export_brep

    buf = io.BytesIO()
    export_brep(shape, buf)
    return buf.getvalue()


def read_brep(path: str | os.PathLike):
    from build123d import import_brep

    return import_brep(str(path))


#: how many times :func:`tessellate` meshes finer (tolerance / 4, angle / 2 each) while a face has
#: no triangles
MESH_RETRIES = 3


def _untriangulated(wrapped) -> int:
    """How many faces of a meshed shape have no triangulation."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    n = 0
    explorer = TopExp_Explorer(wrapped, TopAbs_FACE)
    while explorer.More():
        if BRep_Tool.Triangulation_s(TopoDS.Face_s(explorer.Current()), TopLoc_Location()) is None:
            n += 1
        explorer.Next()
    return n


def tessellate(shape, tolerance: float, angular_tolerance: float = ANGULAR_TOLERANCE_RAD
               ) -> tuple[np.ndarray, np.ndarray]:
    """BRepMesh triangulation of ``shape`` as (vertices (n,3) float64, faces (m,3) int64),
    with the nodes shared by adjacent faces merged (so closed solids give closed meshes).

    At a coarse tolerance a sliver face can get no triangles (OCCT's writer then skips it with a
    warning, and the mesh has a hole): then the shape is meshed finer (tolerance / 4, angle / 2,
    up to :data:`MESH_RETRIES` times) until every face has triangles. A face without triangles
    even then is an error. (The STL's mesh is checked closed where it is written, ``check_mesh``.)

    The triangles are collected by OCCT's StlAPI_Writer (C++, per face, orientation
    handled) into a temporary binary STL, so the vertices are float32-exact values."""
    for k in range(MESH_RETRIES + 1):
        mesh = _mesh(shape.wrapped, tolerance / 4.0 ** k, angular_tolerance / 2.0 ** k)
        if mesh is not None:                # else a face without triangles: finer
            return mesh
    raise RuntimeError(f"{_untriangulated(shape.wrapped)} face(s) get no triangles even at "
                       f"{tolerance / 4.0 ** MESH_RETRIES:g} mm")


def _mesh(wrapped, tolerance: float, angular_tolerance: float):
    """One BRepMesh pass written out through StlAPI_Writer: (vertices, faces), or None where a
    face got no triangles."""
    import tempfile

    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools
    from OCP.StlAPI import StlAPI_Writer

    BRepTools.Clean_s(wrapped)   # drop any coarser/finer mesh left by an earlier call
    BRepMesh_IncrementalMesh(wrapped, tolerance, False, angular_tolerance, False)   # meshes in its constructor
    if _untriangulated(wrapped):
        return None
    writer = StlAPI_Writer()
    writer.ASCIIMode = False
    fd, tmp = tempfile.mkstemp(suffix=".stl", prefix="phantom-tess-")
    os.close(fd)
    try:
        if not writer.Write(wrapped, tmp):
            raise RuntimeError("StlAPI_Writer failed (a face has no triangulation?)")
        with open(tmp, "rb") as fh:
            data = fh.read()
    finally:
        os.unlink(tmp)
    v, f = read_stl(data)
    if len(f) == 0:
        raise RuntimeError("the shape has no faces")
    return v, f


def transform_shape(shape, T: np.ndarray):
    """A copy of ``shape`` moved by the 4x4 homogeneous transform ``T`` (mm)."""
    from OCP.gp import gp_Trsf

    trsf = gp_Trsf()
    T = np.asarray(T, dtype=float)
    trsf.SetValues(*T[0, :4], *T[1, :4], *T[2, :4])
    from build123d import Location

    return shape.moved(Location(trsf))


# ---------------------------------------------------------------------------
# pure mesh helpers

def merge_vertices(vertices: np.ndarray, faces: np.ndarray, tol: float = 1e-9
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Merge coincident vertices (closer than ``tol`` mm: BRepMesh computes the node of an
    edge once per adjacent face, sometimes 1 ulp apart); drop degenerate triangles.
    Deterministic: vertices come out sorted lexicographically."""
    from scipy.spatial import cKDTree

    vertices = np.asarray(vertices, dtype=np.float64) + 0.0  # -0.0 -> 0.0
    # the distinct rows in lexicographic order (np.unique(axis=0), without its structured sort)
    order = np.lexsort(vertices.T[::-1])
    ordered = vertices[order]
    first = np.ones(len(ordered), bool)
    first[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    inverse = np.empty(len(vertices), np.int64)
    inverse[order] = np.cumsum(first) - 1
    uniq = ordered[first]
    faces = inverse[faces]
    pairs = cKDTree(uniq).query_pairs(tol, output_type="ndarray")
    if len(pairs):
        parent = np.arange(len(uniq))

        def root(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for a, b in sorted(map(tuple, pairs)):
            ra, rb = root(a), root(b)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
        rep = np.array([root(i) for i in range(len(uniq))])
        used, remap = np.unique(rep, return_inverse=True)
        uniq, faces = uniq[used], remap[faces]
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    return uniq, faces[keep]


def to_print_pose(vertices: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotate by ``rotation`` then translate so the mesh rests on z = 0, centred in x, y.
    Returns (vertices, 4x4 transform applied)."""
    R = np.asarray(rotation, dtype=float)
    v = vertices @ R.T
    lo, hi = v.min(axis=0), v.max(axis=0)
    shift = np.array([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = shift
    return v + shift, T


def stl_bytes(vertices: np.ndarray, faces: np.ndarray, name: str, unit: str = "mm") -> bytes:
    """Binary STL with a fixed header (no timestamp): byte-identical for the same mesh."""
    v = np.asarray(vertices, dtype=np.float64)
    tri = v[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    record = np.dtype([("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    data = np.zeros(len(faces), dtype=record)
    data["n"] = normals
    data["v"] = tri
    header = f"phantom_cad binary STL: {name} ({unit})".encode("ascii", "replace")[:80].ljust(80, b" ")
    return header + struct.pack("<I", len(faces)) + data.tobytes()


def read_stl(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """Read binary STL bytes back (vertices merged), for tests and checks."""
    (count,) = struct.unpack_from("<I", data, 80)
    record = np.dtype([("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    arr = np.frombuffer(data, dtype=record, count=count, offset=84)
    return merge_vertices(arr["v"].reshape(-1, 3).astype(np.float64), np.arange(3 * count).reshape(-1, 3))


def mesh_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    tri = vertices[faces]
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0)


def check_mesh(name: str, vertices: np.ndarray, faces: np.ndarray, solid_volume: float | None = None,
               rel_volume_tol: float = 1e-2) -> dict:
    """Watertight, consistently wound, positive volume (trimesh) and a valid manifold
    (manifold3d status NoError); optionally the mesh volume matches the solid's.
    Raises :class:`CheckError`; returns the measured figures."""
    import manifold3d
    import trimesh

    tm = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    if not tm.is_watertight:
        raise CheckError(name, "STL watertight", "trimesh: the mesh has open edges")
    if not tm.is_volume:
        raise CheckError(name, "STL is_volume", "trimesh: not a consistently wound closed volume")
    mf = manifold3d.Manifold(manifold3d.Mesh(vert_properties=np.asarray(vertices, dtype=np.float32),
                                             tri_verts=np.asarray(faces, dtype=np.uint32)))
    status = mf.status()
    if status != manifold3d.Error.NoError:
        raise CheckError(name, "STL manifold", f"manifold3d status {status}")
    vol = float(tm.volume)
    if solid_volume is not None and abs(vol - solid_volume) > rel_volume_tol * solid_volume:
        raise CheckError(name, "STL volume", f"mesh volume {vol:.3f} mm^3 vs solid {solid_volume:.3f} mm^3")
    return {"watertight": True, "is_volume": True, "manifold": str(status).split(".")[-1],
            "mesh_volume_mm3": vol, "triangles": int(len(faces))}



