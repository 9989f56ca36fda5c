"""The pictures' rasterizer (export/render.py), against answers worked out by hand: pixel counts
of triangles and squares, the depth order of two crossing triangles, the projected area of a
cube (the sum of |n . d| over its faces, halved, times a face's area), and the PNG written."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from PIL import Image

from phantom_cad.export import render


def _cube(a: float, centre=(0.0, 0.0, 0.0)):
    """A closed cube of side a: 8 vertices, 12 outward triangles (written out by hand)."""
    c = np.asarray(centre, float)
    v = np.array([[x, y, z] for x in (0, a) for y in (0, a) for z in (0, a)], float) - a / 2 + c
    # vertex index = 4 x + 2 y + z (x, y, z in {0, 1})
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    f = []
    for q in quads:
        f += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
    return v, np.array(f)


def test_view_basis_is_matplotlibs_view_init():
    B = render.view_basis(0.0, 0.0)
    assert np.allclose(B, [[0, 1, 0], [0, 0, 1], [1, 0, 0]])       # from +x: y right, z up
    B = render.view_basis(90.0, -90.0)
    assert np.allclose(B[2], [0, 0, 1])                           # from above
    B = render.view_basis(22.0, -58.0)
    assert np.allclose(B @ B.T, np.eye(3)) and np.allclose(np.cross(B[0], B[1]), B[2])
    assert B[1, 2] > 0                                            # z points up the screen


def test_a_triangle_covers_its_area():
    """A right triangle, legs 100 and 60 px at a fractional offset: 3,000 px^2; the pixels whose
    centres lie inside differ from it by less than half its perimeter."""
    tri = np.array([[[10.3, 20.7, 0.0], [110.3, 20.7, 0.0], [10.3, 80.7, 0.0]]])
    index, depth = render.rasterize(tri, 200, 120)
    n = int((index == 0).sum())
    assert abs(n - 3000.0) < (100 + 60 + math.hypot(100, 60)) / 2
    assert np.all(depth[index == 0] == 0.0) and np.all(np.isneginf(depth[index < 0]))


def test_a_shared_edge_is_filled_once():
    """A 40 x 40 px square split along its diagonal, which passes through pixel centres: the two
    triangles, rasterized apart, cover the 1,600 pixels exactly between them."""
    a = [10.0, 20.0, 0.0]
    b = [50.0, 20.0, 0.0]
    c = [50.0, 60.0, 0.0]
    d = [10.0, 60.0, 0.0]
    one, _ = render.rasterize(np.array([[a, b, c]]), 80, 80)
    two, _ = render.rasterize(np.array([[a, c, d]]), 80, 80)
    assert (one == 0).sum() + (two == 0).sum() == 1600
    assert not np.any((one == 0) & (two == 0))
    both, _ = render.rasterize(np.array([[a, b, c], [a, c, d]]), 80, 80)
    assert (both >= 0).sum() == 1600


def test_crossing_triangles_show_the_nearer_one_at_each_pixel():
    """Triangle A rises toward the viewer with x (depth = x), B is level at depth 50: left of x = 50
    B is nearer, right of it A (a painter's sort by centroid shows one of them everywhere)."""
    A = [[0.0, 0.0, 0.0], [100.0, 0.0, 100.0], [50.0, 100.0, 50.0]]
    B = [[0.0, 0.0, 50.0], [100.0, 0.0, 50.0], [50.0, 100.0, 50.0]]
    index, depth = render.rasterize(np.array([A, B]), 100, 100)
    assert index[10, 30] == 1 and depth[10, 30] == pytest.approx(50.0)
    assert index[10, 70] == 0 and depth[10, 70] == pytest.approx(70.5)
    assert np.all(index[5, 52:90] == 0) and np.all(index[5, 10:49] == 1)


@pytest.mark.parametrize("elev, azim", [(22.0, -58.0), (28.0, -62.0), (0.0, 0.0), (62.0, -75.0)])
def test_a_cube_covers_its_projected_area(elev, azim):
    """A convex body's orthographic shadow is half the sum of |n . d| A over its faces: a^2
    (|d_x| + |d_y| + |d_z|) for a cube of side a, viewed along d."""
    a, s = 30.0, 10.0                       # mm, pixels per mm
    v, f = _cube(a)
    B = render.view_basis(elev, azim)
    q = v @ B.T
    px = np.stack([300 + q[:, 0] * s, 300 - q[:, 1] * s, q[:, 2] * s], axis=1)
    index, _ = render.rasterize(px[f], 600, 600)
    want = a * a * np.abs(B[2]).sum() * s * s
    assert (index >= 0).sum() == pytest.approx(want, rel=0.01)
    # and only the three faces toward the viewer show (outward normals: n . d > 0)
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    shown = set(np.unique(index[index >= 0]).tolist())
    assert all(n[k] @ B[2] > -1e-9 for k in shown)


def test_render_png_writes_a_deterministic_picture(tmp_path):
    v, f = _cube(20.0, (0.0, 0.0, 10.0))
    items = [render.MeshItem("cube", v, f, (0.2, 0.4, 0.8), label="cube")]
    p1, p2 = tmp_path / "a.png", tmp_path / "b.png"
    render.render_png(items, p1, "a cube", subtitle="20 mm", size_px=400, bed=True)
    render.render_png(items, p2, "a cube", subtitle="20 mm", size_px=400, bed=True)
    assert p1.read_bytes() == p2.read_bytes()
    im = np.asarray(Image.open(io.BytesIO(p1.read_bytes())).convert("RGB")).astype(int)
    assert im.shape == (400, 400, 3)
    # the cube's blue in the middle of the picture's lower part, the bed's grey, white elsewhere
    blue = (im[:, :, 2] > im[:, :, 0] + 60)
    grey = (np.abs(im[:, :, 0] - 224) <= 2) & (np.abs(im[:, :, 2] - 224) <= 2)
    assert blue.sum() > 0.05 * 400 * 400 and grey.sum() > 0.05 * 400 * 400
    assert np.all(im[0:5, 0:5] == 255)


def test_a_closed_mesh_skips_its_far_side_unseen(tmp_path):
    """A closed, outward-wound cube drawn with its far triangles skipped gives the same picture as
    with every triangle; wound inside out and declared closed, only its inside would show, so the
    picture differs (the skip is by winding, not by depth)."""
    v, f = _cube(20.0, (0.0, 0.0, 10.0))
    pics = {}
    for name, faces, closed in (("all", f, False), ("front", f, True), ("inverted", f[:, ::-1], True)):
        p = tmp_path / f"{name}.png"
        render.render_png([render.MeshItem("cube", v, faces, (0.2, 0.4, 0.8), closed=closed)], p, "a cube",
                          size_px=300, bed=True)
        pics[name] = p.read_bytes()
    assert pics["front"] == pics["all"]
    assert pics["inverted"] != pics["all"]
