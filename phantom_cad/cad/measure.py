"""Measurements of built solids, read from the B-rep (faces, edges, booleans), never from the
parameters: what the part families' ``verify`` methods and the tests compare with the
parameters and closed forms. Units: mm. build123d is imported lazily.
"""

from __future__ import annotations

import math

import numpy as np


def _bd():
    import build123d
    return build123d


def _vec(v) -> np.ndarray:
    return np.array([v.X, v.Y, v.Z], float)


# ---------------------------------------------------------------------------
# solids
# ---------------------------------------------------------------------------

def solid_report(shape) -> dict:
    """Number of solids, validity, volume and bounding box of a shape."""
    bb = shape.bounding_box()
    valid = shape.is_valid      # a property in build123d 0.12 (each read runs BRepCheck), a method before
    valid = valid() if callable(valid) else valid
    return {
        "n_solids": len(shape.solids()),
        "valid": bool(valid),
        "volume": float(shape.volume),
        "bbox_min": _vec(bb.min),
        "bbox_max": _vec(bb.max),
    }


def mass_properties(shape) -> dict:
    """Volume (mm^3), centre of mass (mm) and the inertia tensor about it (mm^5, unit density)
    of a solid, in the shape's own frame (OpenCascade's volume properties)."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape.wrapped, props)
    c = props.CentreOfMass()
    m = props.MatrixOfInertia()          # about the centre of mass, for density 1
    inertia = [[m.Value(i, j) for j in (1, 2, 3)] for i in (1, 2, 3)]
    return {"volume_mm3": float(props.Mass()), "com_mm": [c.X(), c.Y(), c.Z()], "inertia_mm5": inertia}


def placed(shape, T: np.ndarray):
    """The shape moved by a 4x4 rigid transform (mm)."""
    from .parts.common import transform
    return transform(shape, T)


def intersection_volume(a, b) -> float:
    """Volume (mm^3) common to two solids (0 when their bounding boxes are apart)."""
    ba, bb = a.bounding_box(), b.bounding_box()
    if (ba.max.X < bb.min.X or bb.max.X < ba.min.X or ba.max.Y < bb.min.Y or bb.max.Y < ba.min.Y
            or ba.max.Z < bb.min.Z or bb.max.Z < ba.min.Z):
        return 0.0
    common = a.intersect(b)
    if common is None:
        return 0.0
    solids = common.solids() if hasattr(common, "solids") else [s for c in common for s in c.solids()]
    return float(sum(s.volume for s in solids))


# ---------------------------------------------------------------------------
# cylindrical features
# ---------------------------------------------------------------------------

def cylinders(shape):
    """Every cylindrical face: dicts with radius, axis point, axis direction, face centre,
    axial extent (length along the axis) and the face itself."""
    bd = _bd()
    out = []
    for f in shape.faces():
        if f.geom_type != bd.GeomType.CYLINDER:
            continue
        from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
        cyl = BRepAdaptor_Surface(f.wrapped).Cylinder()
        ax = cyl.Axis()
        loc, dr = ax.Location(), ax.Direction()
        p = np.array([loc.X(), loc.Y(), loc.Z()])
        d = np.array([dr.X(), dr.Y(), dr.Z()])
        d /= np.linalg.norm(d)
        radius = cyl.Radius()
        verts = np.array([_vec(v) for v in f.vertices()]) if f.vertices() else np.zeros((0, 3))
        # axial extent from the face's edges (9 points each, evenly in the curve's parameter),
        # robust to seams
        pts = []
        for e in f.edges():
            c = BRepAdaptor_Curve(e.wrapped)
            for t in np.linspace(c.FirstParameter(), c.LastParameter(), 9):
                q = c.Value(t)
                pts.append((q.X(), q.Y(), q.Z()))
        pts = np.array(pts) if pts else verts
        s = (pts - p) @ d
        out.append({
            "radius": float(radius), "point": p, "direction": d,
            "s_min": float(s.min()), "s_max": float(s.max()),
            "length": float(s.max() - s.min()),
            "centre": p + d * float((s.max() + s.min()) / 2.0),
            "face": f,
        })
    return out


def point_line_distance(p, a, d) -> float:
    d = np.asarray(d, float) / np.linalg.norm(d)
    v = np.asarray(p, float) - np.asarray(a, float)
    return float(np.linalg.norm(v - (v @ d) * d))


def coaxial(c, point, direction, tol: float = 1e-3) -> bool:
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    return abs(abs(c["direction"] @ d) - 1.0) < tol and point_line_distance(c["point"], point, d) < tol


def measure_groove_radius(shape, axis_point, axis_direction, width: float, tol: float = 1e-3,
                          faces: list[dict] | None = None) -> float:
    """Radius of the groove bottom about an axis: the coaxial cylindrical face whose axial length
    equals the groove ``width`` (a groove is a short concave band) and whose radius is the
    smallest such band beyond the bore (if several bands, the outermost is the pulley flange).
    ``faces``: ``cylinders(shape)``, when the caller measures several grooves of one shape."""
    cs = [c for c in (cylinders(shape) if faces is None else faces) if coaxial(c, axis_point, axis_direction, tol)
          and abs(c["length"] - width) < 1e-3]
    if not cs:
        raise ValueError("no coaxial cylindrical band of that width")
    # the groove bottom is concave toward the outside: the band whose radius is not a bore
    # (bores are longer than the groove); when both flanges and bottom match, take the smallest
    return float(min(c["radius"] for c in cs))


def eyelet_centres(shape, radius: float, length: float, tol: float = 1e-3, faces: list[dict] | None = None
                   ) -> list[dict]:
    """Guide eyelets: full cylindrical holes of ``radius`` whose axial length is ``length``;
    returns their axis direction and the centre of the band (the guide point). ``faces``:
    ``cylinders(shape)``, when the caller has them."""
    out = []
    for c in (cylinders(shape) if faces is None else faces):
        if abs(c["radius"] - radius) < tol and abs(c["length"] - length) < 0.005:
            out.append({"centre": c["centre"], "direction": c["direction"], "length": c["length"]})
    return out


def circular_pockets(shape, radius: float, tol: float = 1e-3, faces: list[dict] | None = None) -> list[dict]:
    """Blind round pockets of ``radius``: for each such cylindrical face, the centre of its
    opening (the end not closed by a flat bottom face) and the outward direction (bottom ->
    opening). ``faces``: ``cylinders(shape)``, when the caller has them."""
    bd = _bd()
    pockets = [c for c in (cylinders(shape) if faces is None else faces) if abs(c["radius"] - radius) <= tol]
    if not pockets:
        return []
    # each plane's centre and normal once (OpenCascade's surface properties: the costly part)
    planes = []
    for f in shape.faces():
        if f.geom_type == bd.GeomType.PLANE:
            centre = f.center()
            planes.append((f, _vec(centre), _vec(f.normal_at(centre))))
    out = []
    for c in pockets:
        p, d = c["point"], c["direction"]
        ends = [p + d * c["s_min"], p + d * c["s_max"]]
        closed = []
        for e in ends:
            hit = False
            for f, centre, n in planes:
                if abs(abs(n @ d) - 1.0) < 1e-6 and abs((e - centre) @ n) < 1e-6 \
                        and f.area < math.pi * radius * radius * 1.01 and \
                        np.linalg.norm(centre - e) < 1e-3:
                    hit = True
            closed.append(hit)
        if closed[0] == closed[1]:
            continue
        bottom, opening = (ends[0], ends[1]) if closed[0] else (ends[1], ends[0])
        u = opening - bottom
        out.append({"centre": opening, "facing": u / np.linalg.norm(u), "depth": float(np.linalg.norm(u))})
    return out


def planar_faces(shape, min_area: float = 0.0):
    bd = _bd()
    out = []
    for f in shape.faces():
        if f.geom_type == bd.GeomType.PLANE and f.area >= min_area:
            out.append({"centre": _vec(f.center()), "normal": _vec(f.normal_at(f.center())), "area": float(f.area),
                        "face": f})
    return out
