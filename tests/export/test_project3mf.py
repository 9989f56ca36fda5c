"""The parts' PrusaSlicer projects (``print/<part>.3mf``, export/project3mf.py), read back with
zipfile and ElementTree (not the writer), measured with trimesh's ray casting, and sliced by
PrusaSlicer: the support blockers over the tendon features cover only overhangs that bridge
between close walls, and with them no support stands in a groove or channel."""

from __future__ import annotations

import io
import json
import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from phantom_cad.params import load_params

trimesh = pytest.importorskip("trimesh")

HERE = Path(__file__).resolve().parent
CORE = "{http://schemas.microsoft.com/3dmanufacturing/core/2015/02}"
#: the widest bridge the blockers may cover: the widest groove is 1.9 mm (tendons.BRIDGE_MM)
BRIDGE_MM = 2.0
#: a face looking down more steeply than this from the vertical is an overhang (export/orient.py)
OVERHANG_DEG = 45.0


def read_project(path):
    """{"name", "volumes": [(name, type, vertices (bed frame), faces)]} of a PrusaSlicer 3MF."""
    with zipfile.ZipFile(path) as z:
        names = z.namelist()
        model = ET.fromstring(z.read("3D/3dmodel.model"))
        config = ET.fromstring(z.read("Metadata/Slic3r_PE_model.config"))
        rels = z.read("_rels/.rels").decode()
    assert "[Content_Types].xml" in names and "/3D/3dmodel.model" in rels
    objects = model.findall(f"{CORE}resources/{CORE}object")
    assert len(objects) == 1 and len(model.findall(f"{CORE}build/{CORE}item")) == 1
    mesh = objects[0].find(f"{CORE}mesh")
    V = np.array([[float(e.get(k)) for k in "xyz"] for e in mesh.iter(f"{CORE}vertex")])
    F = np.array([[int(e.get(k)) for k in ("v1", "v2", "v3")] for e in mesh.iter(f"{CORE}triangle")])
    vols = []
    obj = config.find("object")
    for vol in obj.findall("volume"):
        meta = {m.get("key"): m.get("value") for m in vol.findall("metadata")}
        a, b = int(vol.get("firstid")), int(vol.get("lastid"))
        f = F[a:b + 1]
        used = np.unique(f)
        remap = np.full(len(V), -1)
        remap[used] = np.arange(len(used))
        vols.append((meta["name"], meta["volume_type"], V[used], remap[f]))
    # the volumes' triangle ranges tile the object's triangles
    assert sum(len(v[3]) for v in vols) == len(F)
    name = {m.get("key"): m.get("value") for m in obj.findall("metadata")}["name"]
    return {"name": name, "volumes": vols}


@pytest.fixture(scope="module")
def hand(hand_build):
    result, _ = hand_build
    return result, json.loads((result.out_dir / "manifest.json").read_text())


def test_every_part_has_its_project(hand):
    """Each part's 3MF holds the STL's mesh (the same float32 vertices, moved onto the bed centre)
    as its one model part, and closed, outward blockers, as many as the manifest says; the
    digit parts have some, the palm and the servo pulleys none."""
    result, man = hand
    with_blockers = 0
    for p in man["parts"]:
        rel = f"print/{p['name']}.3mf"
        assert man["files"][rel]["kind"] == "print_project"
        proj = read_project(result.out_dir / rel)
        assert proj["name"] == p["name"]
        kinds = [v[1] for v in proj["volumes"]]
        assert kinds[0] == "ModelPart" and kinds[1:] == ["SupportBlocker"] * p["support_blockers"]
        stl = trimesh.load(result.out_dir / "stl" / f"{p['name']}.stl", force="mesh", process=False)
        _, _, V, F = proj["volumes"][0]
        assert len(F) == len(stl.faces)
        sv = np.asarray(stl.vertices)
        shift = np.array([100.0, 100.0, 0.0]) - np.r_[(sv.min(0) + sv.max(0))[:2] / 2.0, 0.0]
        theirs = np.unique(sv, axis=0)
        assert len(V) == len(theirs)
        assert cKDTree(theirs).query(V - shift)[0].max() < 1e-5
        assert trimesh.Trimesh(V, F).volume == pytest.approx(p["volume_mm3"], rel=1e-2)
        for label, _, bv, bf in proj["volumes"][1:]:
            b = trimesh.Trimesh(bv, bf, process=True)
            assert b.is_watertight and b.is_winding_consistent and b.volume > 0.0, (p["name"], label)
        with_blockers += p["support_blockers"] > 0
        if p["digit"] is None:
            assert p["support_blockers"] == 0, p["name"]
    assert with_blockers == 4 * 4 + 3


def test_project_bytes_are_deterministic(hand):
    from phantom_cad.export import project3mf

    result, man = hand
    proj = read_project(result.out_dir / "print" / "index_proximal.3mf")
    vols = proj["volumes"]
    blockers = [(label, V, F) for label, _, V, F in vols[1:]]
    a = project3mf.project_bytes("index_proximal", vols[0][2], vols[0][3], blockers)
    assert a == project3mf.project_bytes("index_proximal", vols[0][2], vols[0][3], blockers)
    with zipfile.ZipFile(io.BytesIO(a)) as z:
        assert {i.date_time for i in z.infolist()} == {(1980, 1, 1, 0, 0, 0)}


def bridge_spans(mesh, blocker_V, blocker_F, axes: int = 8):
    """For each overhang face (off the bed) of the mesh (a ``trimesh.Trimesh``, z up) whose centre
    lies in the blocker: the narrowest horizontal extent of the air just under it, over ``axes``
    directions, from the nearest surface one way to the nearest the other (ray casting). A layer
    there closes a gap that wide: a bridge when it is short; unbounded (inf) where the air is open
    to one side."""
    n, c = mesh.face_normals, mesh.triangles_center
    down = (n[:, 2] < -np.sin(np.radians(OVERHANG_DEG))) & (c[:, 2] > 1e-3)
    lo, hi = blocker_V.min(0), blocker_V.max(0)
    idx = np.flatnonzero(down & np.all((c >= lo) & (c <= hi), axis=1))
    if len(idx):
        idx = idx[trimesh.Trimesh(blocker_V, blocker_F, process=False).contains(c[idx])]
    if not len(idx):
        return np.zeros(0)
    o = c[idx] - np.array([0.0, 0.0, 0.005])
    # a sliver face at a concave edge has material just under it: it is no overhang
    air = ~mesh.contains(o)
    idx, o = idx[air], o[air]
    if not len(idx):
        return np.zeros(0)
    ang = np.arange(axes) * np.pi / axes
    A = np.c_[np.cos(ang), np.sin(ang), np.zeros(axes)]
    dirs = np.concatenate([A, -A])
    O, D = np.repeat(o, len(dirs), axis=0), np.tile(dirs, (len(o), 1))
    loc, ray, _ = mesh.ray.intersects_location(O, D, multiple_hits=False)
    d = np.full(len(O), np.inf)
    d[ray] = np.linalg.norm(loc - O[ray], axis=1)
    d = d.reshape(len(o), 2, axes)
    return (d[:, 0] + d[:, 1]).min(axis=1)


def test_bridge_spans_known_answers():
    """A flat roof over a 1.5 mm slot spans 1.5 mm; a round floor in the same slot (a groove's)
    spans no more; a shelf open on three sides spans nothing (unbounded)."""
    roof = trimesh.boolean.difference([trimesh.creation.box((10, 20, 10)),
                                       trimesh.creation.box((1.5, 30, 6)).apply_translation((0, 0, -2))])
    roof.apply_translation((0, 0, 5))
    blk = trimesh.creation.box((1.6, 40, 20))
    s = bridge_spans(roof, blk.vertices, blk.faces)
    assert len(s) >= 2 and s.max() == pytest.approx(1.5, abs=1e-6)
    groove = trimesh.creation.box((10, 20, 10)).difference(
        trimesh.creation.annulus(r_min=3.0, r_max=8.0, height=1.5, sections=64,
                                 transform=trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0))))
    groove.apply_translation((0, 0, 5))
    s = bridge_spans(groove, blk.vertices + (0, 0, 5), blk.faces)
    assert len(s) > 10 and s.max() <= 1.5 + 1e-6
    shelf = trimesh.boolean.union([trimesh.creation.box((2, 2, 10)),
                                   trimesh.creation.box((10, 2, 1)).apply_translation((4, 0, 4.5))])
    shelf.apply_translation((0, 0, 5))
    blk = trimesh.creation.box((20, 20, 20))
    s = bridge_spans(shelf, blk.vertices, blk.faces)
    assert len(s) and np.isinf(s.max())


@pytest.mark.parametrize("kind", ["default", "left", "hand_length_170"])
def test_blockers_cover_only_bridges(kind, hand_export):
    """Every overhang inside a blocker of a part's project spans at most BRIDGE_MM of air between
    walls, in some horizontal direction: it prints as a bridge, and blocking support there takes
    none away that the part needs. Measured on the projects' own meshes, for the three
    reference hands: the default, its left twin and the 170 mm hand (the left one's blockers are
    mirrored with its parts)."""
    result = hand_export(kind)
    man = json.loads((result.out_dir / "manifest.json").read_text())
    assert sum(p["support_blockers"] > 0 for p in man["parts"]) == 4 * 4 + 3
    worst = {}
    for p in man["parts"]:
        if not p["support_blockers"]:
            continue
        vols = read_project(result.out_dir / "print" / f"{p['name']}.3mf")["volumes"]
        mesh = trimesh.Trimesh(vols[0][2], vols[0][3], process=False)
        for label, _, bv, bf in vols[1:]:
            s = bridge_spans(mesh, bv, bf)
            worst[(p["name"], label)] = float(s.max()) if len(s) else 0.0
    assert worst and max(worst.values()) <= BRIDGE_MM, {k: v for k, v in worst.items() if v > BRIDGE_MM}
    # the grooves' floors are measured: their spans are the grooves' widths
    assert max(v for (n, label), v in worst.items() if label.startswith("groove")) >= 0.9


@pytest.fixture(scope="module")
def sliced(hand):
    """PrusaSlicer's automatic supports in the index finger's and the thumb's parts' tendon
    features, each part sliced from its project ({name: features with support}), and the index
    proximal phalanx sliced from its STL."""
    from phantom_cad.export import slicer, supports

    if slicer.find_slicer() is None:
        pytest.skip("prusa-slicer is not installed (bash .ci/sysdeps installs Debian's prusa-slicer)")
    result, man = hand
    params = load_params()
    ini = slicer.config_ini(params.print)
    out, stl = {}, None
    for p in man["parts"]:
        if p["digit"] not in ("index", "thumb"):
            continue
        path = result.out_dir / "stl" / f"{p['name']}.stl"
        r = supports.part_support(params, path, p["print_transform"], p["name"], ini,
                                  project=result.out_dir / "print" / f"{p['name']}.3mf")
        out[p["name"]] = {k: v for k, v in r["features"].items() if v > 0.0}
        if p["name"] == "index_proximal":
            stl = supports.part_support(params, path, p["print_transform"], p["name"], ini)
    return out, stl


def test_blockers_keep_support_out_of_the_index_finger_tendon_features(sliced):
    """The index finger's four parts (magnet face or dorsal face down: every joint axis flat):
    no support path in a groove or channel. Sliced as a bare STL, the proximal phalanx takes
    support in its grooves (the measure sees it)."""
    found, stl = sliced
    index = {n: f for n, f in found.items() if n.startswith("index_")}
    assert len(index) == 4 and all(f == {} for f in index.values()), index
    assert sum(v for k, v in stl["features"].items() if k.startswith("groove")) > 50.0, stl


def test_blockers_keep_support_out_of_the_thumb_phalanges(sliced):
    found, _ = sliced
    assert found["thumb_proximal"] == {} and found["thumb_distal"] == {}, found


def test_tendon_grooves_and_channels_print_without_support(sliced):
    """Sliced from its project, with PrusaSlicer's automatic supports, no support path lies in a
    tendon groove or channel (``export.supports``) of the index finger's and the thumb's parts:
    the thumb CMC base too, on its palmar pad (laid on its side instead, its MP hub groove's inner
    flank would be a 3.8 mm cantilever over the groove, with support standing in it)."""
    found, _ = sliced
    assert len(found) == 7 and "thumb_cmc_base" in found and all(v == {} for v in found.values()), found


@pytest.mark.parametrize("kind", ["left", "hand_length_170"])
def test_the_cmc_base_prints_without_support_in_its_tendon_features_on_the_other_hands(kind, hand_export):
    """The same on the left hand and the 170 mm hand: the thumb CMC base, sliced from its project,
    has no support path in a tendon groove or channel (the left hand's support and solid mirrored
    back into the right hand's link frame, where the routing model's features are)."""
    from phantom_cad.export import slicer, supports

    if slicer.find_slicer() is None:
        pytest.skip("prusa-slicer is not installed (bash .ci/sysdeps installs Debian's prusa-slicer)")
    result = hand_export(kind)
    params = load_params(HERE.parents[1] / "params" / "examples" / "small.toml") if kind == "hand_length_170" \
        else load_params()
    man = json.loads((result.out_dir / "manifest.json").read_text())
    p = next(q for q in man["parts"] if q["name"] == "thumb_cmc_base")
    stl = result.out_dir / "stl" / "thumb_cmc_base.stl"
    assert p["support_blockers"] >= 2 and (result.out_dir / "print" / "thumb_cmc_base.3mf").is_file()
    r = supports.part_support(params, stl, p["print_transform"], "thumb_cmc_base", slicer.config_ini(params.print),
                              project=result.out_dir / "print" / "thumb_cmc_base.3mf", side=result.side)
    assert r["total_mm"] > 25.0    # the part takes support elsewhere (under the MP boss, the arm)
    found = r["features"]
    assert found and all(x == 0.0 for x in found.values()), found
