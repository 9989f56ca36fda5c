"""PNG renders of tessellated parts and of the assembly: a z-buffer rasterizer in numpy, text
by Pillow. No display, no matplotlib.

Orthographic view from (``elev``, ``azim``) degrees, as matplotlib's ``view_init``: the viewer
looks from azimuth ``azim`` in the xy plane (from +x toward +y) and elevation ``elev`` above it,
z up on the screen. Each triangle is flat shaded: its item's colour scaled by a two-sided
Lambert term for a light fixed to the viewer. Every pixel shows the triangle nearest the viewer
there (a z-buffer, so interpenetrating or badly ordered triangles are drawn as they lie), with
``SUPERSAMPLE`` x ``SUPERSAMPLE`` samples a pixel averaged; depth steps (silhouettes, occluding
contours) are drawn as dark lines. ``bed``: the items rest on z = 0 (print orientation) on a
grey bed with a 10 mm grid. A scale bar gives millimetres. A label is drawn once, over what
shows of the items that carry it (``label_anchor``): never over another item that hides them;
where two labels' texts would overlap, the later one moves to the nearest of its own items'
pixels where it stands clear (``place_labels``).

The PNG carries no timestamp and the sampling is fixed, so the same meshes give the same bytes.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from .. import units

#: light direction in the viewer's frame (right, up, toward the viewer), normalised below
_LIGHT = np.array([-0.4, 0.6, 0.7])
_AMBIENT = 0.35
#: samples per pixel along each axis
SUPERSAMPLE = 2
#: the bed's grid pitch (mm)
BED_GRID_MM = 10.0
_BACKGROUND = np.array([1.0, 1.0, 1.0])
_BED = np.array([0.88, 0.88, 0.88])
_BED_LINE = np.array([0.72, 0.72, 0.72])
_OUTLINE = np.array([0.12, 0.12, 0.14])
#: a depth step larger than this fraction of the view's size is an outline
_OUTLINE_STEP = 0.01
#: a label stays at its first item's projected top point when its items show within this many
#: pixels (of the picture) beside or below it; else it moves over what shows of them
LABEL_REACH = 6
#: the pixels (of the picture) kept free around a label's text, apart from another label
LABEL_GAP = 2


@dataclass
class MeshItem:
    name: str
    vertices: np.ndarray    # (n, 3) mm, already placed in the render frame
    faces: np.ndarray       # (m, 3)
    color: tuple[float, float, float]
    #: text drawn once over what shows of the items that carry it (a digit's name on each of its
    #: parts, say); None = no label; nothing is drawn when none of them shows
    label: str | None = None
    #: a closed mesh with outward triangles (counter-clockwise seen from outside, as the STLs
    #: are, checked by ``step_stl.check_mesh``): the triangles facing away are never seen and
    #: are skipped; False draws every triangle
    closed: bool = False


def view_basis(elev: float, azim: float) -> np.ndarray:
    """Rows (right, up, toward the viewer) of the orthographic view (world frame, unit)."""
    e, a = units.rad(elev), units.rad(azim)
    toward = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    right = np.array([-math.sin(a), math.cos(a), 0.0])
    return np.vstack([right, np.cross(toward, right), toward])


def rasterize(tri: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Z-buffer of triangles given in pixel space: ``tri`` (m, 3, 3) as (x right, y down, depth
    toward the viewer), pixel (i, j) covering [i, i+1) x [j, j+1). A pixel belongs to a triangle
    when its centre lies inside (edges shared by two triangles are filled once: rows by the
    half-open rule along y, columns along x). Returns (index, depth): (height, width) arrays of
    the nearest triangle's index (-1 where none) and its depth there (-inf where none)."""
    tri = np.asarray(tri, dtype=np.float64)
    x, y, z = tri[:, :, 0], tri[:, :, 1], tri[:, :, 2]
    # the depth's plane per triangle: z = z0 + gx (px - x0) + gy (py - y0)
    e1x, e1y, e1z = x[:, 1] - x[:, 0], y[:, 1] - y[:, 0], z[:, 1] - z[:, 0]
    e2x, e2y, e2z = x[:, 2] - x[:, 0], y[:, 2] - y[:, 0], z[:, 2] - z[:, 0]
    det = e1x * e2y - e2x * e1y
    ok = np.abs(det) > 1e-12
    sd = np.where(ok, det, 1.0)
    gx = (e1z * e2y - e2z * e1y) / sd
    gy = (e2z * e1x - e1z * e2x) / sd
    # the corners from the lowest to the highest y: each edge is then computed from its lower end
    # by every triangle that has it (the same bits on both sides of a shared edge)
    o = np.argsort(y, axis=1, kind="stable")
    ys, xs = np.take_along_axis(y, o, axis=1), np.take_along_axis(x, o, axis=1)
    # rows whose centres (j + 0.5) lie in the triangle's y range, half-open: y0 <= j + 0.5 < y2
    j0 = np.clip(np.ceil(ys[:, 0] - 0.5), 0, height).astype(np.int64)
    j1 = np.clip(np.ceil(ys[:, 2] - 0.5), 0, height).astype(np.int64)     # exclusive
    rows = np.where(ok, np.maximum(j1 - j0, 0), 0)
    t = np.repeat(np.arange(len(tri)), rows)
    start = np.cumsum(rows) - rows
    j = j0[t] + (np.arange(len(t)) - start[t])
    yc = j + 0.5
    # the row's span: between the long edge (lowest to highest corner), which every row crosses,
    # and the short edge it crosses, below the middle corner (y0 <= yc < y1) or from it on
    Y, X = ys[t], xs[t]
    xlong = X[:, 0] + (yc - Y[:, 0]) * (X[:, 2] - X[:, 0]) / (Y[:, 2] - Y[:, 0])
    low = yc < Y[:, 1]
    ya, yb = np.where(low, Y[:, 0], Y[:, 1]), np.where(low, Y[:, 1], Y[:, 2])
    xa, xb = np.where(low, X[:, 0], X[:, 1]), np.where(low, X[:, 1], X[:, 2])
    xshort = xa + (yc - ya) * (xb - xa) / (yb - ya)
    xl, xr = np.minimum(xlong, xshort), np.maximum(xlong, xshort)
    valid = xr > xl
    t, j, yc, xl, xr = t[valid], j[valid], yc[valid], xl[valid], xr[valid]
    i0 = np.clip(np.ceil(xl - 0.5), 0, width).astype(np.int64)
    i1 = np.clip(np.ceil(xr - 0.5), 0, width).astype(np.int64)                  # exclusive
    n = np.maximum(i1 - i0, 0)
    s = np.repeat(np.arange(len(t)), n)
    first = np.cumsum(n) - n
    i = i0[s] + (np.arange(len(s)) - first[s])
    t, j, yc = t[s], j[s], yc[s]
    depth = z[t, 0] + gx[t] * (i + 0.5 - x[t, 0]) + gy[t] * (yc - y[t, 0])
    k = j * width + i
    zbuf = np.full(width * height, -np.inf)
    np.maximum.at(zbuf, k, depth)
    win = depth >= zbuf[k]
    index = np.full(width * height, -1, dtype=np.int64)
    index[k[win]] = t[win]              # equal depths: the later triangle (deterministic)
    return index.reshape(height, width), zbuf.reshape(height, width)


def label_anchor(mine: np.ndarray, p: tuple[float, float], reach: float) -> tuple[float, float] | None:
    """Where a label stands (its bottom centre, pixel coordinates (x right, y down) of ``mine``,
    the pixels that show the label's items): at ``p`` (the projection of its first item's top
    point) when they show within ``reach`` pixels of it, beside or below; else (the top point
    is hidden behind another item) at the centroid of their pixels, or at the centre of their
    pixel nearest that centroid when the centroid falls on another item; None when none of
    them shows (a label there would name another item)."""
    h, w = mine.shape
    x, y = p
    r0, r1 = int(max(math.floor(y), 0)), int(min(math.floor(y + reach) + 1, h))
    c0, c1 = int(max(math.floor(x - reach), 0)), int(min(math.floor(x + reach) + 1, w))
    if r0 < r1 and c0 < c1 and np.any(mine[r0:r1, c0:c1]):
        return (x, y)
    rows, cols = np.nonzero(mine)
    if not len(rows):
        return None
    x, y = float(cols.mean()) + 0.5, float(rows.mean()) + 0.5
    if mine[int(y), int(x)]:
        return (x, y)
    m = int(np.argmin((cols + 0.5 - x) ** 2 + (rows + 0.5 - y) ** 2))
    return (float(cols[m]) + 0.5, float(rows[m]) + 0.5)


def place_labels(labels: list[tuple[tuple[float, float, float, float], tuple[float, float] | None,
                                     np.ndarray]], stride: int = 4
                 ) -> list[tuple[float, float] | None]:
    """Where each label is drawn so that no two labels' boxes overlap, placed in turn (first
    come, first placed). Each label is (box, anchor, mine): ``box`` its text's extent (left, top,
    right, bottom) relative to the point it is drawn at, ``anchor`` where ``label_anchor`` puts
    it (None: not drawn), ``mine`` the pixels that show its items. A label whose box at its
    anchor overlaps no label placed before stays there; else it moves to the nearest (to its
    anchor) of its items' pixels, taken every ``stride`` pixels along rows and columns, where its
    box overlaps none and lies inside the picture; where there is none, it stays at its anchor
    (the overlap is then drawn). Pixel coordinates (x right, y down) of ``mine``."""
    placed: list[tuple[float, float, float, float]] = []
    out: list[tuple[float, float] | None] = []

    def clear(x, y, box, h, w):
        """(n,) whether the box drawn at each (x, y) stays inside the picture and off every placed
        box."""
        l, t, r, b = box
        ok = (x + l >= 0) & (x + r <= w) & (y + t >= 0) & (y + b <= h)
        for pl, pt, pr, pb in placed:
            ok &= (x + r <= pl) | (x + l >= pr) | (y + b <= pt) | (y + t >= pb)
        return ok

    for box, at, mine in labels:
        if at is None:
            out.append(None)
            continue
        where = at
        if not clear(np.array([at[0]]), np.array([at[1]]), box, math.inf, math.inf)[0]:
            rows, cols = np.nonzero(mine[::stride, ::stride])
            x, y = cols * stride + 0.5, rows * stride + 0.5
            ok = clear(x, y, box, *mine.shape)
            if ok.any():
                d = (x - at[0]) ** 2 + (y - at[1]) ** 2
                d[~ok] = np.inf
                m = int(np.argmin(d))       # the first of equally near ones: deterministic
                where = (float(x[m]), float(y[m]))
        l, t, r, b = box
        placed.append((where[0] + l, where[1] + t, where[0] + r, where[1] + b))
        out.append(where)
    return out


def _shade(normals: np.ndarray, light: np.ndarray, color: np.ndarray) -> np.ndarray:
    """(m, 3) flat colours of triangles with these (unnormalised) normals under a unit ``light``
    direction (same frame): two-sided Lambert."""
    n = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    k = _AMBIENT + (1.0 - _AMBIENT) * np.abs(n @ light)
    return np.clip(color[None, :] * k[:, None], 0.0, 1.0)


def _rgb8(c) -> tuple[int, int, int]:
    return tuple(int(round(float(v) * 255.0)) for v in c)


@lru_cache(maxsize=None)
def _font(size: int):
    """DejaVu Sans (matplotlib ships it; found without importing matplotlib), else Pillow's own."""
    import importlib.util

    from PIL import ImageFont

    spec = importlib.util.find_spec("matplotlib")
    for root in (spec.submodule_search_locations or []) if spec else []:
        path = Path(root) / "mpl-data" / "fonts" / "ttf" / "DejaVuSans.ttf"
        if path.is_file():
            return ImageFont.truetype(str(path), size)
    try:
        return ImageFont.load_default(size=size)
    except (TypeError, OSError):       # Pillow without FreeType: the bitmap font
        return ImageFont.load_default()


def _fitting(text: str, size: int, width: float):
    """The font at ``size`` points, or smaller (down to 6) until ``text`` fits in ``width`` pixels."""
    font = _font(size)
    while size > 6 and font.getlength(text) > width:
        size -= 1
        font = _font(size)
    return font


def _nice(x: float) -> float:
    """The largest 1, 2 or 5 x 10^n not above x."""
    p = 10.0 ** math.floor(math.log10(x))
    return max(m * p for m in (1.0, 2.0, 5.0) if m * p <= x)


def render_png(items: list[MeshItem], path: str | os.PathLike, title: str, *,
               elev: float = 22.0, azim: float = -58.0, size_px: int = 900,
               subtitle: str | None = None, bed: bool = False) -> None:
    """Render ``items`` into a ``size_px`` square PNG at ``path``. ``bed``: the items rest on
    z = 0 (print orientation); a bed with a 10 mm grid is drawn under them."""
    from PIL import Image, ImageDraw

    B = view_basis(elev, azim)
    S = SUPERSAMPLE
    W = H = size_px * S
    top = int(0.12 * H)                      # the title's band
    pts = np.vstack([it.vertices for it in items])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    corners = pts
    bed_sq = None
    if bed:
        c = (lo + hi) / 2.0
        # whole grid squares, at least half a square beyond the items
        half = BED_GRID_MM * math.ceil((max(hi[0] - lo[0], hi[1] - lo[1]) / 2.0 + BED_GRID_MM / 2.0) / BED_GRID_MM)
        bed_sq = (c[0] - half, c[0] + half, c[1] - half, c[1] + half)
        corners = np.vstack([pts, [[bed_sq[a], bed_sq[b], 0.0] for a in (0, 1) for b in (2, 3)]])
    v2 = corners @ B[:2].T
    span = np.maximum(v2.max(axis=0) - v2.min(axis=0), 1e-6)
    margin = 0.06 * W
    scale = min((W - 2 * margin) / span[0], (H - top - 2 * margin) / span[1])     # pixels per mm
    mid = (v2.max(axis=0) + v2.min(axis=0)) / 2.0
    cx, cy = W / 2.0, top + (H - top) / 2.0

    def to_px(p):
        q = p @ B.T
        return np.stack([cx + (q[..., 0] - mid[0]) * scale, cy - (q[..., 1] - mid[1]) * scale, q[..., 2] * scale],
                        axis=-1)

    light = B.T @ (_LIGHT / np.linalg.norm(_LIGHT))     # the viewer's light in the world frame
    tris, colors = [], []
    for it in items:
        tri = np.asarray(it.vertices, float)[np.asarray(it.faces)]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        if it.closed:
            front = n @ B[2] > 0.0
            tri, n = tri[front], n[front]
        tris.append(to_px(tri))
        colors.append(_shade(n, light, np.asarray(it.color, float)))
    tri_px = np.concatenate(tris) if tris else np.zeros((0, 3, 3))
    color = np.concatenate(colors) if colors else np.zeros((0, 3))
    index, depth = rasterize(tri_px, W, H)
    # where the labels go: over what shows of their items (before the window below crops index)
    groups: dict[str, list[int]] = {}
    for k, it in enumerate(items):
        if it.label:
            groups.setdefault(it.label, []).append(k)
    anchors, masks = {}, {}
    if groups:
        item_group = np.full(len(items), -1)
        for g, ks in enumerate(groups.values()):
            item_group[ks] = g
        shown = np.full(index.shape, -1)                 # the label group each pixel shows
        hit = index >= 0
        shown[hit] = np.repeat(item_group, [len(t) for t in tris])[index[hit]]
        for g, (label, ks) in enumerate(groups.items()):
            c = np.asarray(items[ks[0]].vertices, float)
            top_pt = c.mean(axis=0)
            top_pt[2] = c[:, 2].max()
            masks[label] = shown == g
            anchors[label] = label_anchor(masks[label], tuple(to_px(top_pt[None, :])[0, :2]), LABEL_REACH * S)
    canvas = Image.new("RGB", (W, H), _rgb8(_BACKGROUND))
    if bed_sq is not None:
        pen = ImageDraw.Draw(canvas)
        x0, x1, y0, y1 = bed_sq
        quad = to_px(np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]]))
        pen.polygon([tuple(p[:2]) for p in quad], fill=_rgb8(_BED))
        n = int(round((x1 - x0) / BED_GRID_MM))
        for k in range(n + 1):
            g = k * BED_GRID_MM
            for a, b in (((x0 + g, y0), (x0 + g, y1)), ((x0, y0 + g), (x1, y0 + g))):
                ends = to_px(np.array([[*a, 0.0], [*b, 0.0]]))
                pen.line([tuple(ends[0, :2]), tuple(ends[1, :2])], fill=_rgb8(_BED_LINE), width=S)
    img = np.asarray(canvas).copy()
    # the window of the items' pixels, one pixel wider: the outlines lie in it (two background
    # pixels have no depth step between them)
    hit = index >= 0
    rows, cols = np.flatnonzero(hit.any(axis=1)), np.flatnonzero(hit.any(axis=0))
    if len(rows):
        win = np.s_[max(rows[0] - 1, 0):rows[-1] + 2, max(cols[0] - 1, 0):cols[-1] + 2]
        index, depth, hit, sub = index[win], depth[win], hit[win], img[win]
        sub[hit] = np.round(color * 255.0).astype(np.uint8)[index[hit]]
        # outlines: a depth step to a neighbour (or to the background) of more than a fraction of
        # the view's size
        d = np.where(hit, depth, -1e30).astype(np.float32)
        step = _OUTLINE_STEP * max(W, H)
        edge = np.zeros(d.shape, bool)
        for a, b in ((np.s_[1:, :], np.s_[:-1, :]), (np.s_[:, 1:], np.s_[:, :-1])):
            diff = d[a] - d[b]
            edge[a] |= diff > step            # the nearer side carries the line
            edge[b] |= diff < -step
        sub[edge] = _rgb8(_OUTLINE)
    # SUPERSAMPLE x SUPERSAMPLE samples per pixel
    out = Image.fromarray(img, "RGB").reduce(S)       # each pixel the mean of its S x S samples
    draw = ImageDraw.Draw(out)
    ink = (20, 20, 20)
    f_small = _font(max(10, size_px // 75))
    draw.text((size_px / 2, 0.02 * size_px), title, fill=ink, font=_fitting(title, max(12, size_px // 45), 0.96 * size_px),
              anchor="mt")
    if subtitle:
        draw.text((size_px / 2, 0.065 * size_px), subtitle, fill=(80, 80, 80),
                  font=_fitting(subtitle, max(10, size_px // 70), 0.96 * size_px), anchor="mt")
    # apart from one another: each text's box (drawn 4 px above its point, with its stroke) and
    # LABEL_GAP pixels around it, in the supersampled pixels of the masks
    boxes = [tuple(S * np.add(f_small.getbbox(label, anchor="mb", stroke_width=2),
                              (-LABEL_GAP, -4 - LABEL_GAP, LABEL_GAP, -4 + LABEL_GAP)))
             for label in anchors]
    spots = place_labels([(box, at, masks[label]) for box, (label, at) in zip(boxes, anchors.items())],
                         stride=2 * S)
    for label, at in zip(anchors, spots):
        if at is not None:
            p = np.asarray(at) / S
            draw.text((p[0], p[1] - 4), label, fill=ink, font=f_small, anchor="mb", stroke_width=2,
                      stroke_fill=(255, 255, 255))
    # scale bar, bottom left: a round length near a fifth of the picture
    mm_px = scale / S
    length = _nice(0.2 * size_px / mm_px)
    x0, y0 = 0.04 * size_px, 0.96 * size_px
    x1 = x0 + length * mm_px
    draw.line([(x0, y0), (x1, y0)], fill=ink, width=max(2, size_px // 300))
    for xe in (x0, x1):
        draw.line([(xe, y0 - 4), (xe, y0 + 4)], fill=ink, width=1)
    draw.text(((x0 + x1) / 2, y0 - 6), f"{length:g} mm", fill=ink, font=f_small, anchor="mb")
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    out.save(path, format="PNG", optimize=False)
