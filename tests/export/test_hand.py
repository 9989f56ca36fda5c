"""The default hand with the real parts (phantom_cad.cad), built once per session (with slicing).

Everything is re-measured from the exported files with independent readers: trimesh and
manifold3d for the STLs, build123d's STEP reader, PrusaSlicer's G-code comments.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from phantom_cad.params import load_params

trimesh = pytest.importorskip("trimesh")
manifold3d = pytest.importorskip("manifold3d")


@pytest.fixture(scope="module")
def hand(hand_build):
    result, cache = hand_build
    man = json.loads((result.out_dir / "manifest.json").read_text())
    return result, man


def _stl(out, name):
    return trimesh.load(out / "stl" / f"{name}.stl", force="mesh")


def test_every_part_exported(hand):
    from phantom_cad.cad import assembly

    result, man = hand
    names = assembly.part_names(load_params())
    assert [p["name"] for p in man["parts"]] == names
    for n in names:
        for rel in (f"step/{n}.step", f"stl/{n}.stl", f"renders/{n}.png"):
            assert (result.out_dir / rel).is_file(), rel
            assert rel in man["files"]
    assert (result.out_dir / "renders" / "hand_assembly.png").stat().st_size > 20_000
    # the measured verification (phantom_cad.cad.verify) ran on every part and passed
    assert {p["checks"]["verify_part"] for p in man["parts"]} == {"ok"}
    assert (result.out_dir / "bom.csv").read_text().startswith("category,item,specification,quantity,unit,")


def test_stls_watertight_manifold_on_the_bed(hand):
    result, man = hand
    for p in man["parts"]:
        mesh = _stl(result.out_dir, p["name"])
        assert mesh.is_watertight and mesh.is_volume, p["name"]
        m = manifold3d.Manifold(manifold3d.Mesh(vert_properties=np.asarray(mesh.vertices, np.float32),
                                                tri_verts=np.asarray(mesh.faces, np.uint32)))
        assert m.status() == manifold3d.Error.NoError, p["name"]
        assert mesh.bounds[0][2] == pytest.approx(0.0, abs=1e-4), p["name"]
        assert mesh.volume == pytest.approx(p["volume_mm3"], rel=1e-2), p["name"]


def _support_area(mesh, R):
    """(area facing down more steeply than 45 deg from vertical and off the bed, area on the bed,
    footprint) of an STL mesh rotated by R, resting on z = 0: trimesh's face normals and areas."""
    v = np.asarray(mesh.vertices) @ R.T
    v[:, 2] -= v[:, 2].min()
    normals = np.asarray(mesh.face_normals) @ R.T
    areas = np.asarray(mesh.area_faces)
    top = v[np.asarray(mesh.faces)][:, :, 2].max(axis=1)
    down = normals[:, 2] < -np.sqrt(0.5)
    bed = top <= 1e-3
    ext = np.ptp(v, axis=0)
    return areas[down & ~bed].sum(), areas[down & bed].sum(), ext[0] * ext[1]


def test_each_part_prints_in_the_orientation_of_least_overhang(hand):
    """The exported STL (in its print orientation) needs no more support than the same mesh turned
    onto any of its 24 axis-aligned orientations that rest it on a flat face (on-bed faces at
    least a quarter of the footprint); measured on the written file, within 1 mm^2."""
    import itertools

    result, man = hand
    turns = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            R = np.zeros((3, 3))
            R[np.arange(3), perm] = signs
            if np.linalg.det(R) > 0:
                turns.append(R)
    worse = {}
    for p in man["parts"]:
        mesh = _stl(result.out_dir, p["name"])
        mine, bed, footprint = _support_area(mesh, np.eye(3))
        assert bed >= 0.25 * footprint, p["name"]
        best = min(a for a, b, fp in (_support_area(mesh, R) for R in turns) if b >= 0.25 * fp)
        assert p["overhang_mm2"] == pytest.approx(mine, abs=1.0), p["name"]
        if mine > best + 1.0:
            worse[p["name"]] = (round(mine, 1), round(best, 1))
    assert worse == {}


def test_step_reimports_to_the_same_volume(hand):
    from build123d import import_step

    result, man = hand
    for p in man["parts"]:
        shape = import_step(str(result.out_dir / "step" / f"{p['name']}.step"))
        assert len(shape.solids()) == 1, p["name"]
        assert shape.volume == pytest.approx(p["volume_mm3"], rel=1e-3), p["name"]
    asm = import_step(str(result.out_dir / "step" / "hand_assembly.step"))
    assert len(asm.solids()) == len(man["parts"])
    assert sum(s.volume for s in asm.solids()) == pytest.approx(
        sum(p["volume_mm3"] for p in man["parts"]), rel=1e-3)


def test_no_unplanned_intersection_at_rest(hand):
    """Recomputed from the STL files: undo the print transform, place with T_hand_link,
    intersect every pair with manifold3d."""
    from phantom_cad.cad import assembly
    from phantom_cad.export.pipeline import INTERFERENCE_TOL_MM3

    result, man = hand
    allowed = {frozenset(c[:2]) for c in assembly.designed_contacts(load_params())}
    solids = {}
    for p in man["parts"]:
        mesh = _stl(result.out_dir, p["name"])
        P = np.asarray(p["print_transform"])
        T = np.asarray(p["T_hand_link"]) @ np.linalg.inv(P)
        v = mesh.vertices @ T[:3, :3].T + T[:3, 3]
        solids[p["name"]] = manifold3d.Manifold(manifold3d.Mesh(
            vert_properties=v.astype(np.float32), tri_verts=np.asarray(mesh.faces, np.uint32)))
    names = list(solids)
    bad = []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            if frozenset((a, b)) in allowed:
                continue
            vol = (solids[a] ^ solids[b]).volume()
            if vol > INTERFERENCE_TOL_MM3:
                bad.append((a, b, round(vol, 3)))
    assert bad == []
    assert man["assembly"]["interference"]["collisions"] == []


def test_every_part_slices(hand):
    from phantom_cad.export import slicer

    if slicer.find_slicer() is None:
        pytest.skip("prusa-slicer is not installed (bash .ci/sysdeps installs Debian's prusa-slicer)")
    result, man = hand
    assert man["slicer"]["used"] is True
    infill = load_params().print.infill
    for p in man["parts"]:
        est = p["print"]
        assert est is not None and est["time_s"] > 0, p["name"]
        vol_cm3 = p["volume_mm3"] / 1000.0
        # at least the infill fraction of the solid, at most the solid (no supports)
        assert infill * vol_cm3 * 0.9 < est["filament_cm3"] < vol_cm3 * 1.1, p["name"]
    assert man["totals"]["print_time_s"] == sum(p["print"]["time_s"] for p in man["parts"])
    # the fit-test coupon is sliced too (not in the hand's totals)
    est, vol_cm3 = man["coupon"]["print"], man["coupon"]["volume_mm3"] / 1000.0
    assert est is not None and est["time_s"] > 0
    assert infill * vol_cm3 * 0.9 < est["filament_cm3"] < vol_cm3 * 1.1


def test_mass_estimates(hand):
    result, man = hand
    params = load_params()
    for p in man["parts"]:
        # g = mm^3 * 1e-3 cm^3/mm^3 * g/cm^3 * infill
        known = p["volume_mm3"] * 1e-3 * (params.document["print"]["density_g_per_cm3"]) * params.print.infill
        assert p["mass_g"] == pytest.approx(known, rel=1e-6)
        assert man["files"][f"stl/{p['name']}.stl"]["sha256"]


def _read_back_print_aid(out, man, kind: str, name: str) -> dict:
    """A print aid's manifest entry, after reading its files back: every file listed with its kind,
    the STEP one solid of the manifest's volume (build123d), the STL watertight, on the bed and of
    the STEP's volume (trimesh)."""
    from build123d import import_step

    e = man[kind]
    for rel in (e["step"], e["stl"], e["sheet"], f"{kind}/{name}.png"):
        assert (out / rel).is_file() and man["files"][rel]["kind"] == kind, rel
    step = import_step(str(out / e["step"]))
    assert len(step.solids()) == 1 and step.volume == pytest.approx(e["volume_mm3"], rel=1e-6)
    mesh = trimesh.load(out / e["stl"], force="mesh")
    assert mesh.is_watertight and mesh.is_volume
    assert mesh.bounds[0][2] == pytest.approx(0.0, abs=1e-4)
    assert mesh.volume == pytest.approx(step.volume, rel=1e-2)
    return e


def test_exported_coupon(hand):
    """The export's fit-test coupon, read back: the STL with trimesh (watertight, on the bed, the
    STEP's volume), the STEP with build123d, the manifest's holes by hand, the maker's sheet."""
    result, man = hand
    out, c = result.out_dir, _read_back_print_aid(result.out_dir, man, "coupon", "fit_coupon")
    # by hand from params/phantom.toml: 7 mm bearing - 0.05 interference + 0.2 compensation; 0.6 mm
    # tendon + 2 x 0.2 clearance, not compensated; 5 mm magnet + 2 x 0.1 + 0.2
    holes = {f["key"]: f for f in c["features"]}
    assert holes["bearing_seat"]["modelled_mm"] == pytest.approx(7.15)
    assert holes["bearing_seat"]["fit_mm"] == pytest.approx(6.95)
    assert holes["tendon_channel_h"]["modelled_mm"] == pytest.approx(1.0)
    assert holes["magnet_pocket"]["modelled_mm"] == pytest.approx(5.4)
    sheet = (out / c["sheet"]).read_text()
    assert all(f"| {k} |" in sheet for k in holes)


def test_exported_gauge(hand):
    """The export's angle gauge, read back: the STL with trimesh (watertight, on the bed, the STEP's
    volume), the STEP with build123d, the manifest's faces (0 to 105 degrees for params/phantom.toml,
    whose PIPs reach 92.2), the maker's sheet."""
    result, man = hand
    out, g = result.out_dir, _read_back_print_aid(result.out_dir, man, "gauge", "angle_gauge")
    assert [f["angle_deg"] for f in g["faces"]] == [15.0 * k for k in range(8)]
    assert [f["marks"] for f in g["faces"]] == list(range(8))
    sheet = (out / g["sheet"]).read_text()
    assert all(f"| {a:g} |" in sheet for a in range(0, 106, 15))


def test_verify_part_problem_refuses_the_part(hand_build, monkeypatch, tmp_path):
    """A problem reported by phantom_cad.cad.verify.verify_part fails the part with its text."""
    from phantom_cad.cad import verify as check
    from phantom_cad.canon import plain as _plain
    from phantom_cad.export.pool import part_worker as _part_worker
    from phantom_cad.params import DEFAULT_PARAMS, load_document

    monkeypatch.setattr(check, "verify_part",
                        lambda params, name, shape: [f"{name}: groove radius measures 6.0000, expected 7.0000 mm"])
    r = _part_worker({"name": "servo_pulley_1", "key": "k", "document": _plain(load_document(DEFAULT_PARAMS)),
                      "source": str(DEFAULT_PARAMS), "cache_root": str(tmp_path), "render": False})
    assert r["ok"] is False
    f = r["failure"]
    assert f["check"] == "verify_part"
    assert f["error"] == ("CheckError: part 'servo_pulley_1': check 'verify_part' failed: "
                          "servo_pulley_1: groove radius measures 6.0000, expected 7.0000 mm")
    assert not (tmp_path / "parts" / "k").exists()


def test_the_same_parameters_give_the_same_bytes_whoever_built_the_parts(hand_build, tmp_path):
    """The default hand built again from nothing with one process (every part, the coupon and the
    assembly written one after another in this one: OpenCascade numbers a STEP file's assembly
    occurrences from a counter that lives as long as the process) gives the same bytes, file by
    file, as the session's build with two workers (which wrote the five servo pulleys, the CMC
    pulley and the forearm, each one assembly occurrence, in whichever worker came free). The
    slicer's estimates are carried over (PrusaSlicer is not run-to-run deterministic): they are
    served only for STL files with the same SHA-256."""
    import hashlib
    import shutil

    from phantom_cad.export.pipeline import build_hand

    result, cache = hand_build
    if (cache / "slice").is_dir():
        shutil.copytree(cache / "slice", tmp_path / "cache" / "slice")
    again = build_hand(None, tmp_path / "out", cache_dir=tmp_path / "cache", jobs=1, slice=None)
    assert again.built == result.parts

    def tree(out):
        return {p.relative_to(out).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
                for p in sorted(out.rglob("*")) if p.is_file()}

    a, b = tree(result.out_dir), tree(again.out_dir)
    assert sorted(a) == sorted(b)
    assert [k for k in a if a[k] != b[k]] == []


# -- the orderable BOM -----------------------------------------------------------------------------

def _bom(out) -> list[dict]:
    import csv
    import io

    return list(csv.DictReader(io.StringIO((out / "bom.csv").read_text(encoding="utf-8"))))


def _axis_lines(faces, radius: float) -> set:
    """The distinct axis lines of the cylindrical faces of ``radius`` (a hole through two cheeks,
    or split in faces, is one line)."""
    out = set()
    for c in faces:
        if abs(c["radius"] - radius) <= 1e-3:
            d = c["direction"] * np.sign(c["direction"][np.argmax(np.abs(c["direction"]))])
            foot = c["point"] - np.dot(c["point"], d) * d
            out.add((tuple(np.round(d, 3)), tuple(np.round(foot, 1))))
    return out


def test_bom_lines_match_what_the_built_parts_hold(hand, hand_parts):
    """Each bought part's quantity, counted on the exported solids, not read from the BOM's own
    rows: bearing seats, pressed axle holes (one pin each, of the digit's width), magnet pockets,
    self-tapping pilot holes; the servos (one per servo pulley part), the coupling loops' set
    screws and the split drives' crimp stops from the routing; every printed part in the
    filament line, its mass the slicer's (or the parts' estimate)."""
    from phantom_cad.cad import measure
    from phantom_cad.cad.parts.common import Tolerances
    from phantom_cad.kinematics import couplers, routing

    result, man = hand
    params, solids = hand_parts("default")
    t = Tolerances(params)
    counts = {"seat": 0, "magnet": 0, "pilot": 0}
    pins: dict[float, int] = {}
    digit = {p["name"]: p["digit"] for p in man["parts"]}
    for name, solid in solids.items():
        faces = measure.cylinders(solid)
        counts["seat"] += len(_axis_lines(faces, t.bearing_seat / 2.0))
        counts["magnet"] += len(measure.circular_pockets(solid, t.magnet_pocket_d / 2.0, faces=faces))
        counts["pilot"] += len(measure.circular_pockets(solid, t.screw_pilot / 2.0, faces=faces))
        if (n := len(_axis_lines(faces, t.axle_press / 2.0))):
            width = round(params.digit(digit[name]).width * 1e3, 6)
            pins[width] = pins.get(width, 0) + n
    lines = _bom(result.out_dir)
    qty = lambda item: [float(r["quantity"]) for r in lines if r["item"] == item]  # noqa: E731
    assert qty("ball bearing") == [counts["seat"]] and counts["seat"] > 0
    assert qty("magnet") == [counts["magnet"]] and counts["magnet"] > 0
    assert qty("self-tapping screw") == [counts["pilot"]] and counts["pilot"] > 0
    assert {float(r["specification"].split()[-2]): float(r["quantity"]) for r in lines
            if r["item"] == "dowel pin"} == pins
    n_servos = len([n for n in solids if n.startswith("servo_pulley_")])
    assert qty("servo") == qty("servo cable") == [n_servos]
    assert qty("horn screw") == [2 * n_servos]
    assert qty("set screw") == [len([r for r in routing.routes(params) if r.tendon.kind == "coupling"])]
    assert qty("crimp sleeve") == [len(couplers.couplers(params))]
    # every printed part is in the filament line, by the slicer's filament (or the estimated mass)
    (fil,) = [r for r in lines if r["item"] == "filament"]
    names = [p["name"] for p in man["parts"]]
    assert fil["used_in"].startswith(f"the {len(names)} printed parts ({', '.join(names)}): ")
    grams = sum(p["print"]["filament_g"] if result.sliced else p["mass_g"] for p in man["parts"])
    assert float(fil["quantity"]) == pytest.approx(grams, abs=0.05)
    assert ("not sliced" in fil["used_in"]) == (not result.sliced)


def test_bom_md_totals_add_up_from_bom_csv(hand):
    """bom.md's per-category and hand totals, recomputed from bom.csv's lines; each line's cost
    its packs times its pack's price, and the packs enough for the quantity."""
    import re

    result, man = hand
    lines = _bom(result.out_dir)
    md = (result.out_dir / "bom.md").read_text(encoding="utf-8")
    per: dict[str, float] = {}
    for r in lines:
        q, pack, packs = float(r["quantity"]), float(r["pack_size"]), int(r["packs"])
        assert packs * pack >= q > (packs - 1) * pack, r
        cost = float(r["line_cost"])
        assert cost == pytest.approx(packs * pack * float(r["unit_price"]), abs=0.01), r
        per[r["category"]] = per.get(r["category"], 0.0) + cost
        assert r["specification"] in md and r["used_in"].replace("|", "/") in md
    cur = lines[0]["currency"]
    for c, v in per.items():
        assert f"| {c} | {v:.2f} {cur} |" in md
        assert f"\n{c[0].upper()}{c[1:]}: {v:.2f} {cur}\n" in md
    assert re.search(rf"\| \*\*hand\*\* \| \*\*{sum(per.values()):.2f} {cur}\*\* \|", md)
    # bom.md ends with the assembly list, the manifest's bom
    assembly_list = md[md.index("# Assembly list"):]
    assert all(f"\n| {r['item']} | {r['spec']} | {r['quantity']} | " in assembly_list for r in man["bom"])


def test_docs_bom_md_is_the_default_hands(hand):
    """docs/bom.md ends with the default hand's bom.md as an unsliced `phantom-cad build` writes
    it (the test hand may be sliced: its filament is then replaced by the parts' estimated mass,
    as the build computes it without the slicer)."""
    from phantom_cad.cad import purchase
    from phantom_cad.cad.materials import bill_of_materials
    from phantom_cad.export.bom import bom_md
    from tests.conftest import ROOT

    result, man = hand
    params = load_params()
    grams = sum(p["mass_g"] for p in man["parts"])
    rows = bill_of_materials(params)
    assert man["bom"] == rows
    lines = purchase.order_lines(params, rows, grams, False, tuple(p["name"] for p in man["parts"]))
    if not result.sliced:       # then the build wrote exactly these lines
        assert (result.out_dir / "bom.md").read_text(encoding="utf-8") == bom_md(lines, rows, params.name, False)
    doc = (ROOT / "docs" / "bom.md").read_text(encoding="utf-8")
    marker = "<!-- the default hand's bom.md"
    generated = doc[doc.index("\n", doc.index(marker)) + 2:]
    assert generated == bom_md(lines, rows, params.name, False, level=2), (
        "docs/bom.md is out of date: replace its last section with the default hand's bom.md "
        "(phantom-cad build, unsliced), its headings one level down")
