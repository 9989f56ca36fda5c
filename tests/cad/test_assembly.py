"""The assembly interface (docs/parts.md): names, inputs, poses, contacts, bill of materials."""

from __future__ import annotations

import math
import re
import subprocess
import sys

import numpy as np
import pytest

from phantom_cad.cad import measure
from phantom_cad.cad import assembly
from phantom_cad.kinematics.topology import joint_index

FINGERS = ("index", "middle", "ring", "pinky")


def test_part_names_stable_unique_file_safe(params):
    names = assembly.part_names(params)
    assert names == assembly.part_names(params)
    assert len(names) == len(set(names)) == 1 + 1 + 4 * 4 + 3 + 1 + 6
    assert names[0] == "palm"
    assert all(re.fullmatch(r"[a-z0-9_]+", n) for n in names)
    assert {f"servo_pulley_{k}" for k in range(1, 7)} | {"thumb_cmc_pulley"} <= set(names)


def test_unknown_part_is_refused(params):
    with pytest.raises(KeyError, match="unknown part 'index_claw'"):
        assembly.part_inputs(params, "index_claw")


def test_interface_does_not_import_cad():
    code = (
        "import sys\n"
        "from phantom_cad import load_params\n"
        "from phantom_cad.cad import assembly as A\n"
        "p = load_params()\n"
        "[A.part_inputs(p, n) for n in A.part_names(p)]\n"
        "A.designed_contacts(p); A.bill_of_materials(p); A.pose_transforms(p)\n"
        "bad = [m for m in sys.modules if m.split('.')[0] in ('OCP', 'build123d', 'cadquery')]\n"
        "print(len(bad))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "0"


def test_part_inputs_follow_the_digit(params, variant):
    names = assembly.part_names(params)
    before = {n: assembly.part_inputs(params, n) for n in names}
    p = variant(lambda d: d["fingers"]["ring"].__setitem__("width_mm", 16.5))
    after = {n: assembly.part_inputs(p, n) for n in names}
    changed = {n for n in names if before[n] != after[n]}
    # the palm carries every socket, the forearm module aims every servo at its socket, and the
    # CMC pulley's clamp lies where servo 6's loop arrives from that row
    assert changed == {"palm", "forearm", "ring_base", "ring_proximal", "ring_middle", "ring_distal",
                       "thumb_cmc_pulley"}
    p = variant(lambda d: d["print"].__setitem__("hole_clearance_mm", 0.15))
    after = {n: assembly.part_inputs(p, n) for n in names}
    assert all(before[n] != after[n] for n in names)


def test_pose_transforms_are_rigid_and_rest_by_default(params):
    rest = assembly.pose_transforms(params)
    zero = assembly.pose_transforms(params, np.zeros(15))
    assert rest.keys() == set(assembly.part_names(params))
    for n, T in rest.items():
        assert np.allclose(T, zero[n])
        R = T[:3, :3]
        assert np.allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(rest["palm"], np.eye(4))


def test_mcp_flexion_swings_the_proximal_phalanx_palmar(params, document):
    theta = 0.7
    q = np.zeros(15)
    q[joint_index("index", "mcp")] = theta
    T = assembly.pose_transforms(params, q)
    Lp = document["fingers"]["index"]["length_fraction"]["proximal"] * document["hand"]["hand_length_mm"]
    tip = T["index_proximal"] @ np.array([0.0, Lp, 0.0, 1.0])
    expected = T["index_base"] @ np.array([0.0, Lp * math.cos(theta), -Lp * math.sin(theta), 1.0])
    assert np.allclose(tip, expected, atol=1e-9)
    # the rest of the finger follows rigidly, other fingers do not move
    rest = assembly.pose_transforms(params)
    assert np.allclose(T["middle_distal"], rest["middle_distal"])


def test_cmc_turns_the_thumb_about_its_axis(params):
    q15 = 0.9
    q = np.zeros(15)
    q[14] = q15
    rest, T = assembly.pose_transforms(params), assembly.pose_transforms(params, q)
    o, a = rest["thumb_cmc_base"][:3, 3], rest["thumb_cmc_base"][:3, 2]
    for name in ("thumb_proximal", "thumb_distal"):
        v0 = rest[name][:3, 3] - o
        v1 = T[name][:3, 3] - o
        v0 -= (v0 @ a) * a
        v1 -= (v1 @ a) * a
        assert np.linalg.norm(v0) == pytest.approx(np.linalg.norm(v1))
        assert math.acos(v0 @ v1 / (np.linalg.norm(v0) * np.linalg.norm(v1))) == pytest.approx(q15)
    # the CMC pulley turns with the CMC base about the same axis; servo 6's pulley, like every
    # servo pulley, stays in the link transforms (it turns by u6 in the routing model's poses)
    R = rest["thumb_cmc_pulley"][:3, :3].T @ T["thumb_cmc_pulley"][:3, :3]
    assert math.atan2(R[1, 0], R[0, 0]) == pytest.approx(q15)
    assert T["thumb_cmc_pulley"][:3, 3] - o == pytest.approx((rest["thumb_cmc_pulley"][:3, 3] - o), abs=1e-12)
    assert np.allclose(rest["servo_pulley_6"], T["servo_pulley_6"])


def test_left_hand_poses_are_mirrored(params, variant):
    left = variant(lambda d: d["hand"].__setitem__("side", "left"))
    q = np.linspace(0.0, 0.8, 15)
    R, L = assembly.pose_transforms(params, q), assembly.pose_transforms(left, q)
    S = np.diag([-1.0, 1.0, 1.0, 1.0])
    for n in R:
        assert np.allclose(L[n], S @ R[n] @ S)
        assert L[n][0, 3] == pytest.approx(-R[n][0, 3])


def test_designed_contacts_name_real_parts(params):
    names = set(assembly.part_names(params))
    contacts = assembly.designed_contacts(params)
    assert all(a in names and b in names and why for a, b, why in contacts)
    assert ("index_base", "palm") in {(a, b) for a, b, _ in contacts}


def test_bill_of_materials(params):
    bom = assembly.bill_of_materials(params)
    assert all(set(row) == {"item", "spec", "quantity", "used_in"} for row in bom)
    qty = {}
    for row in bom:
        assert isinstance(row["quantity"], int) and row["quantity"] > 0
        qty[row["item"]] = qty.get(row["item"], 0) + row["quantity"]
    # 14 tendon-driven joints (4 x 3 + thumb 2), one axle each; one bearing where its seat (radius
    # (7 - 0.05) / 2 = 3.475 mm, 3 mm wide from a tongue face) stays 0.8 mm from every groove: at a
    # finger PIP both tongue faces carry a groove (the loop's at the ulnar face, floor 4 - 0.3 =
    # 3.7 mm; the return cord's next to the hub, floor 4 - 0.75 = 3.25 mm), so 2 per finger + 2
    assert qty["bearing"] == 4 * 2 + 2
    assert qty["axle"] == 14
    # two magnets per finger base and two per palm socket
    assert qty["magnet"] == 16
    assert qty["servo"] == 6
    # a drive per tendon servo (5), split in two strands for the four magnet-held fingers (+4), a
    # coupling loop per pair of adjacent joints (4 x 2 + 1), the CMC loop (1), a return cord per
    # digit (5); a crimp stop per split drive
    assert qty["tendon"] == 5 + 4 + 9 + 1
    assert qty["cable spring"] == 5
    assert qty["crimp stop"] == 4
    # every tendon's cut length is its routed length (routing_paths.lengths) plus what its ends need
    from phantom_cad.kinematics import routing_paths
    rest = routing_paths.lengths(params)
    working = {}
    for row in bom:
        if row["item"] == "tendon" and " strand" in row["used_in"].split(":", 1)[0]:
            # a split drive's strand: its working length, and its cut at least that plus two knots
            name = row["used_in"].split(",", 1)[0]
            w = float(re.search(r"(\d+\.\d) mm from the (?:anchor|loop's bight)", row["used_in"]).group(1))
            working[name] = working.get(name, 0.0) + w
            assert w + 40 - 0.5 <= float(re.search(r"(\d+) mm$", row["spec"]).group(1))
            continue
        if row["item"] in ("tendon", "cable spring"):
            name = row["used_in"].split(" ", 1)[0]
            run = sum(v for k, v in rest.items() if k == name or k.startswith(name + "_")) * 1e3
            if row["item"] == "cable spring":
                free = float(re.search(r"(\d+) mm free length", row["spec"]).group(1))
                assert free == pytest.approx(run, abs=0.5)
            else:
                cut = float(re.search(r"(\d+) mm$", row["spec"]).group(1))
                assert run + 40 - 0.5 <= cut
    # the two strands of a split drive add up to the drive's routed length (to their 0.1 mm print)
    assert sorted(working) == ["index_drive", "middle_drive", "pinky_drive", "ring_drive"]
    for name, w in working.items():
        assert w == pytest.approx(rest[name] * 1e3, abs=0.11)
    # the index drive's palm strand reaches from its servo pulley to the socket, 29.3 mm of straight run
    tendon = next(r for r in bom if r["item"] == "tendon" and r["used_in"].startswith("index_drive, palm"))
    length = float(re.search(r"(\d+) mm$", tendon["spec"]).group(1))
    assert length > 29.3 + 40


def test_built_parts_carry_their_placement(built, params):
    rest = assembly.pose_transforms(params)
    for n, b in built.items():
        assert b.name == n
        assert np.allclose(b.T_hand_link, rest[n])
        assert all(0.0 <= c <= 1.0 for c in b.color)
        R = b.print_rotation
        assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
        assert b.digit == (n.split("_")[0] if n.split("_")[0] in FINGERS + ("thumb",) and n != "thumb_cmc_pulley"
                           else None)


def test_print_rotation_lays_each_part_on_a_flat_face(built):
    """After the print rotation, planar faces facing straight down cover a good part of the
    footprint at the lowest z."""
    for n, b in built.items():
        T = np.eye(4)
        T[:3, :3] = b.print_rotation
        s = measure.placed(b.shape, T)
        rep = measure.solid_report(s)
        z0 = rep["bbox_min"][2]
        lo, hi = rep["bbox_min"], rep["bbox_max"]
        footprint = (hi[0] - lo[0]) * (hi[1] - lo[1])
        down = sum(f["area"] for f in measure.planar_faces(s)
                   if f["normal"][2] < -0.999999 and abs(f["centre"][2] - z0) < 1e-6)
        assert down > 0.25 * footprint, (n, down, footprint)


@pytest.mark.parametrize("side", ["right", "left"])
def test_joint_table_reproduces_the_posed_links(params, variant, side):
    """Chaining origin * rotation(axis, q) over link_frames.joints() gives pose_transforms(q)."""
    from phantom_cad.kinematics import link_frames as LF
    p = params if side == "right" else variant(lambda d: d["hand"].__setitem__("side", "left"))
    q = np.linspace(0.1, 0.9, 15)
    table = LF.joints(p)
    assert [j["name"] for j in table][:3] == ["thumb_ip", "thumb_mp", "index_dip"]

    def rot(axis, a):   # Rodrigues, written out here
        k = np.asarray(axis, float)
        K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        T = np.eye(4)
        T[:3, :3] = np.eye(3) + math.sin(a) * K + (1 - math.cos(a)) * K @ K
        return T

    links = {"palm": np.eye(4)}
    fixed = {f"{f}_base": LF.link_transforms(p)[f"{f}_base"] for f in FINGERS}
    links.update(fixed)
    pending = sorted(table, key=lambda j: 0 if j["parent"] in links else 1)
    while pending:
        j = next(j for j in pending if j["parent"] in links)
        pending.remove(j)
        links[j["child"]] = links[j["parent"]] @ j["origin"] @ rot(j["axis"], q[j["q_index"]])
    posed = {n: LF.link_transforms(p, q)[n] for n in links}
    for n, T in links.items():
        assert np.allclose(T, posed[n], atol=1e-12), n
    # limits come from the parameter file
    assert table[2]["limits"] == (0.0, 1.31) and table[14]["limits"] == (0.0, 1.57)
