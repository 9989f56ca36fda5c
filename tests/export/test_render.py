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


def test_a_label_stands_over_what_shows_of_its_item():
    """label_anchor on the pixels of items of an owner map drawn by hand (10 x 12 px, pixel (row r, column c) centred at
    x = c + 0.5, y = r + 0.5): item 0 fills rows 2-3, columns 1-4; item 1 fills rows 6-8, columns
    5-10, and item 2 hides its top at rows 4-5; item 4 is an L whose centroid falls outside it."""
    owner = np.full((10, 12), -1)
    owner[2:4, 1:5] = 0
    owner[6:9, 5:11] = 1
    owner[4:6, 3:11] = 2
    # item 0 shows just below its top point (2.5, 1.6): the label stays there
    assert render.label_anchor(owner == 0, (2.5, 1.6), 1.0) == (2.5, 1.6)
    # item 1's top point (8.0, 4.2) lies on item 2 and item 1 shows only from row 6, two rows
    # below: within 3 px it stays, within 1 px it moves to its pixels' centroid (columns 5-10,
    # rows 6-8: x 8.0, y 7.5)
    assert render.label_anchor(owner == 1, (8.0, 4.2), 3.0) == (8.0, 4.2)
    assert render.label_anchor(owner == 1, (8.0, 4.2), 1.0) == (8.0, 7.5)
    # an item nowhere to be seen has no label
    assert render.label_anchor(owner == 3, (8.0, 4.2), 1.0) is None
    # a top point off the picture: over what shows (item 0's centroid: x 3.0, y 3.0)
    assert render.label_anchor(owner == 0, (-40.0, -40.0), 2.0) == (3.0, 3.0)
    # an L (column 0, rows 0-9, and row 9, columns 1-5: 15 px): its centroid (x 1 + 0.5, y 90 / 15
    # + 0.5 = 6.5) lies off it, on pixel (6, 1); the nearest pixel of the L is (6, 0), 1 px away
    ell = np.full((10, 12), -1)
    ell[:, 0] = 4
    ell[9, 1:6] = 4
    assert render.label_anchor(ell == 4, (50.0, -5.0), 1.0) == (0.5, 6.5)


def test_labels_are_placed_apart_on_their_own_pixels():
    """place_labels on masks drawn by hand (20 x 30 px, pixel (row r, column c) centred at
    (c + 0.5, r + 0.5)), boxes (left, top, right, bottom) of a 6 x 2 px text about its point."""
    box = (-3.0, -2.0, 3.0, 0.0)
    a = np.zeros((20, 30), bool)
    a[2:6, 4:16] = True                      # rows 2-5, columns 4-15
    b = np.zeros((20, 30), bool)
    b[2:12, 12:16] = True                    # rows 2-11, columns 12-15
    # alone, or apart: each at its anchor
    assert render.place_labels([(box, (8.0, 4.0), a)], stride=1) == [(8.0, 4.0)]
    assert render.place_labels([(box, (8.0, 4.0), a), (box, (14.0, 10.0), b)], stride=1) == [(8.0, 4.0), (14.0, 10.0)]
    # the second anchored where the first is: the first stays (its box x 5-11, y 2-4); the second
    # goes to the nearest of its pixels where its box clears the first's: right of it (x - 3 >= 11:
    # x 14.5 on row 3 or 4, distance^2 to (8, 4) 6.5^2 + 0.5^2 = 42.5) or below it (y - 2 >= 4:
    # y 6.5, on column 12: 4.5^2 + 2.5^2 = 26.5, the nearer)
    assert render.place_labels([(box, (8.0, 4.0), a), (box, (8.0, 4.0), b)], stride=1) == [(8.0, 4.0), (12.5, 6.5)]
    # every pixel taken every 2: rows 2, 4, ..., columns 12, 14: the box clears at (12.5, 6.5)
    assert render.place_labels([(box, (8.0, 4.0), a), (box, (8.0, 4.0), b)], stride=2) == [(8.0, 4.0), (12.5, 6.5)]
    # nowhere clear (the second's pixels all under the first's box): it stays, overlapping
    c = np.zeros((20, 30), bool)
    c[3, 7:9] = True
    assert render.place_labels([(box, (8.0, 4.0), a), (box, (8.0, 4.0), c)], stride=1) == [(8.0, 4.0), (8.0, 4.0)]
    # a label not drawn takes no room
    assert render.place_labels([(box, None, a), (box, (8.0, 4.0), b)], stride=1) == [None, (8.0, 4.0)]
    # a box must stay inside the picture (30 x 20): on rows 0-1 its top (y - 2) is above it, on
    # columns 27-29 its right (x + 3) beyond it; of d's pixels only row 9, column 20 is left
    d = np.zeros((20, 30), bool)
    d[0:2, :] = True
    d[:, 27:] = True
    d[9, 20] = True
    assert render.place_labels([(box, (8.0, 4.0), a), (box, (8.0, 4.0), d)], stride=1) == [(8.0, 4.0), (20.5, 9.5)]


def test_a_hidden_item_gets_no_label_and_a_seen_one_does(tmp_path):
    """Seen from +x (y right, z up): a small cube inside a big one (hidden) drawn with a label gives
    the same picture as without it, while the big cube's label changes it. A 16 mm cube behind the
    big one (y 9-25 mm against the big one's -20-20) shows only its strip y 20-25: its top point
    (y 17, z 23) is hidden, and its label stands right of the big cube's edge, over the strip
    (the text's pixels, found by difference with the unlabelled picture)."""
    big_v, big_f = _cube(40.0, (0.0, 0.0, 20.0))
    small_v, small_f = _cube(10.0, (0.0, 0.0, 20.0))

    def pic(name, items):
        path = tmp_path / f"{name}.png"
        render.render_png(items, path, "cubes", elev=0.0, azim=0.0, size_px=300)
        return path.read_bytes()

    def rgb(data):
        return np.asarray(Image.open(io.BytesIO(data)).convert("RGB")).astype(int)

    big = render.MeshItem("big", big_v, big_f, (0.6, 0.6, 0.6), closed=True)
    inside = render.MeshItem("small", small_v, small_f, (0.2, 0.4, 0.8), label="small", closed=True)
    unlabelled = render.MeshItem("small", small_v, small_f, (0.2, 0.4, 0.8), closed=True)
    assert pic("hidden", [big, inside]) == pic("plain", [big, unlabelled])
    big_labelled = render.MeshItem("big", big_v, big_f, (0.6, 0.6, 0.6), label="big", closed=True)
    assert pic("big", [big_labelled, unlabelled]) != pic("plain", [big, unlabelled])

    side_v, side_f = _cube(16.0, (-40.0, 17.0, 15.0))
    a = rgb(pic("seen", [big, render.MeshItem("side", side_v, side_f, (0.2, 0.4, 0.8), label="SIDE",
                                               closed=True)]))
    b = rgb(pic("unseen", [big, render.MeshItem("side", side_v, side_f, (0.2, 0.4, 0.8), closed=True)]))
    grey = (np.abs(b[:, :, 0] - b[:, :, 2]) < 4) & (b[:, :, 0] > 60) & (b[:, :, 0] < 240)
    blue = b[:, :, 2] > b[:, :, 0] + 40
    edge = np.flatnonzero(grey.any(axis=0)).max()            # the big cube's right edge
    strip = np.flatnonzero(blue.any(axis=0))
    assert strip.min() >= edge - 2 and strip.max() > edge + 10    # only the strip shows
    text = np.argwhere(np.abs(a - b).sum(axis=2) > 150)
    assert len(text) > 20
    assert text[:, 1].mean() > edge


def test_a_label_on_several_items_is_drawn_once_over_what_shows(tmp_path):
    """The same label on two items is drawn once: where its first item's top point shows, the
    picture is the one with the label on the first item alone; where the first item is hidden
    (inside the big cube), the label stands over the second (the strip right of the big cube),
    as it would with the second alone."""
    big_v, big_f = _cube(40.0, (0.0, 0.0, 20.0))
    small_v, small_f = _cube(10.0, (0.0, 0.0, 20.0))
    left_v, left_f = _cube(10.0, (30.0, -10.0, 5.0))
    side_v, side_f = _cube(16.0, (-40.0, 17.0, 15.0))

    def item(name, v, f, label=None):
        return render.MeshItem(name, v, f, (0.2, 0.4, 0.8), label=label, closed=True)

    def pic(name, items):
        path = tmp_path / f"{name}.png"
        render.render_png(items, path, "cubes", elev=0.0, azim=0.0, size_px=300)
        return path.read_bytes()

    big = render.MeshItem("big", big_v, big_f, (0.6, 0.6, 0.6), closed=True)
    # both shown (the left cube in front of the big one): drawn once, at the first's top point
    assert pic("both", [big, item("left", left_v, left_f, "D"), item("side", side_v, side_f, "D")]) == \
        pic("first", [big, item("left", left_v, left_f, "D"), item("side", side_v, side_f)])
    # the first hidden: over the second, as with the second alone
    hidden_first = pic("hidden_first", [big, item("inside", small_v, small_f, "D"), item("side", side_v, side_f, "D")])
    assert hidden_first == pic("second", [big, item("inside", small_v, small_f), item("side", side_v, side_f, "D")])
    assert hidden_first != pic("none", [big, item("inside", small_v, small_f), item("side", side_v, side_f)])
