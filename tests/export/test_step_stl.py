"""Deterministic writers: canonical STEP presentation block, binary STL, vertex merging."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad.export import step_stl

HEAD = b"""ISO-10303-21;
HEADER;
FILE_NAME('x','1970-01-01T00:00:00',('Author'),(''),'','','');
ENDSEC;
DATA;
#1 = PRODUCT('a;b','#9','',(#2));
#2 = SHAPE_REPRESENTATION('',(#3),#4);
#3 = AXIS2_PLACEMENT_3D('',#5,#6,#7);
"""
TAIL = b"ENDSEC;\nEND-ISO-10303-21;\n"

# the same presentation block written in two entity orders (as OCCT does from run to run)
BLOCK_A = b"""#10 = MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',(#11),#4);
#11 = STYLED_ITEM('color',(#12),#2);
#12 = PRESENTATION_STYLE_ASSIGNMENT((#13));
#13 = COLOUR_RGB('',0.9,0.5,0.2);
#14 = MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',(#15),#5);
#15 = STYLED_ITEM('color',(#16),#3);
#16 = PRESENTATION_STYLE_ASSIGNMENT((#17));
#17 = COLOUR_RGB('',0.2,0.4,0.9);
"""
BLOCK_B = b"""#10 = MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',(#12),#5);
#11 = COLOUR_RGB('',0.9,0.5,0.2);
#12 = STYLED_ITEM('color',(#13),#3);
#13 = PRESENTATION_STYLE_ASSIGNMENT((#17));
#14 = STYLED_ITEM('color',(#16),#2);
#15 = MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',(#14),#4);
#16 = PRESENTATION_STYLE_ASSIGNMENT((#11));
#17 = COLOUR_RGB('',0.2,0.4,0.9);
"""


# heads the block-only parse (``_split_presentation``) hands back to the whole-file parse: the
# block's keyword in a label before the block, a quoted '#15' (at or past the block's first id)
HEADS = [HEAD,
         HEAD + b"#4 = PRODUCT('MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION','',(#2));\n",
         HEAD + b"#4 = PRODUCT('see #15','',(#2));\n"]


@pytest.mark.parametrize("head", HEADS, ids=["plain", "keyword in a label", "quoted reference"])
def test_canonical_step_block_is_order_independent(head):
    a = step_stl.canonicalize_step(head + BLOCK_A + TAIL)
    b = step_stl.canonicalize_step(head + BLOCK_B + TAIL)
    assert a == b
    # the head (geometry) is untouched, quoted ';' and '#' survive
    assert a.startswith(head)
    assert a.endswith(TAIL)
    # each styled item still points at the right geometry with the right colour
    ents = dict(step_stl._split_entities(a)[1])
    for geometry, rgb in ((b"#2", b"0.9,0.5,0.2"), (b"#3", b"0.2,0.4,0.9")):
        item = next(k for k, body in ents.items() if body.startswith(b"STYLED_ITEM") and body.endswith(geometry + b")"))
        psa = int(ents[item].split(b"(#")[1].split(b")")[0])
        colour = int(ents[psa].split(b"((#")[1].split(b")")[0])
        assert ents[colour] == b"COLOUR_RGB(''," + rgb + b")"


def test_canonical_step_without_block_is_unchanged():
    data = HEAD + TAIL
    assert step_stl.canonicalize_step(data) is data


def test_stl_bytes_layout_and_roundtrip():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    data = step_stl.stl_bytes(v, f, "tetra")
    assert len(data) == 80 + 4 + 50 * 4
    assert data[:80] == b"phantom_cad binary STL: tetra (mm)".ljust(80)
    assert int.from_bytes(data[80:84], "little") == 4
    # the first facet normal: triangle (0,2,1) lies in z = 0, wound clockwise from +z -> (0,0,-1)
    n = np.frombuffer(data[84:96], "<f4")
    assert n.tolist() == [0.0, 0.0, -1.0]
    v2, f2 = step_stl.read_stl(data)
    assert len(v2) == 4 and len(f2) == 4
    assert step_stl.mesh_volume(v2, f2) == pytest.approx(1.0 / 6.0, rel=1e-7)   # unit tetrahedron
    assert step_stl.stl_bytes(v, f, "tetra") == data


def test_merge_vertices_joins_1ulp_neighbours_and_drops_degenerates():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [np.nextafter(1.0, 2.0), 0, 0], [-0.0, 0, 0]])
    f = np.array([[0, 1, 2], [4, 3, 2], [0, 4, 1]])
    mv, mf = step_stl.merge_vertices(v, f)
    # sorted: (0,0,0) [also -0.0], (0,1,0), (1,0,0) [also 1 + 1 ulp]
    assert mv.tolist() == [[0, 0, 0], [0, 1, 0], [1, 0, 0]]
    # (0, 4, 1) collapses (0 and -0.0 are the same vertex) and is dropped
    assert mf.tolist() == [[0, 2, 1], [0, 2, 1]]


def test_check_mesh_reports_open_mesh():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2]])   # one face missing
    with pytest.raises(step_stl.CheckError) as info:
        step_stl.check_mesh("tetra", v, f)
    assert str(info.value) == "part 'tetra': check 'STL watertight' failed: trimesh: the mesh has open edges"


def test_print_pose_rests_on_bed():
    v = np.array([[0, 0, 0], [10, 0, 0], [0, 20, 0], [0, 0, 30]], dtype=float)
    R = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=float)   # +90 deg about x
    vp, T = step_stl.to_print_pose(v, R)
    assert vp[:, 2].min() == 0.0
    assert np.ptp(vp, axis=0).tolist() == [10.0, 30.0, 20.0]
    assert (vp.min(axis=0)[:2] + vp.max(axis=0)[:2]).tolist() == [0.0, 0.0]
    hom = np.c_[v, np.ones(4)] @ T.T
    assert hom[:, :3] == pytest.approx(vp)


def test_occurrence_ids_are_numbered_from_one_in_file_order():
    """OCCT's ids of assembly occurrences ('7', '9', '10' here: the counter of a process that wrote
    others before) become '1', '2', '3' in the order written, each entity on one line (OCCT broke
    the third's line where its two-digit id put the break); labels (a line break inside one
    stays), references and the rest stay."""
    nauo = (b"#20 = NEXT_ASSEMBLY_USAGE_OCCURRENCE('7','palm','',#1,#2,$);\n"
            b"#21 = NEXT_ASSEMBLY_USAGE_OCCURRENCE( '9' ,'see #7','',#1,#3,$);\n"
            b"#22 = NEXT_ASSEMBLY_USAGE_OCCURRENCE('10','a\n  b','',#1,\n  #4,$\n  );\n")
    out = step_stl.canonicalize_step(HEAD + nauo + TAIL)
    assert out == HEAD + (b"#20 = NEXT_ASSEMBLY_USAGE_OCCURRENCE('1','palm','',#1,#2,$);\n"
                          b"#21 = NEXT_ASSEMBLY_USAGE_OCCURRENCE( '2' ,'see #7','',#1,#3,$);\n"
                          b"#22 = NEXT_ASSEMBLY_USAGE_OCCURRENCE('3','a\n  b','',#1,#4,$);\n") + TAIL
    assert step_stl.canonicalize_step(out) == out


def test_an_assembly_written_twice_in_one_process_gives_the_same_bytes():
    """OpenCascade's STEP writer counts assembly occurrences per process: before the ids were
    renumbered, the second file of the same two-box assembly said '3', '4' where the first said
    '1', '2' (a part's STEP depended on what its build worker had written before)."""
    pytest.importorskip("build123d")
    import re

    from build123d import Box, Compound, Pos

    def assembly():
        a = Box(1, 1, 1)
        a.label = "a"
        b = Pos(3, 0, 0) * Box(1, 1, 1)
        b.label = "b"
        return Compound(children=[a, b], label="ab")

    first, second = step_stl.step_bytes(assembly()), step_stl.step_bytes(assembly())
    assert first == second
    assert re.findall(rb"NEXT_ASSEMBLY_USAGE_OCCURRENCE\('(\d+)'", second) == [b"1", b"2"]
