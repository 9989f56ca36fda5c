"""The one topology against the paper's Table I and the hand's tree, typed here by hand."""

from __future__ import annotations

import pytest

from phantom_cad.kinematics import topology as T

# Table I, typed from the paper: q label -> (digit, joint)
TABLE_I = {
    "q1": ("thumb", "ip"), "q2": ("thumb", "mp"),
    "q3": ("index", "dip"), "q4": ("index", "pip"), "q5": ("index", "mcp"),
    "q6": ("middle", "dip"), "q7": ("middle", "pip"), "q8": ("middle", "mcp"),
    "q9": ("ring", "dip"), "q10": ("ring", "pip"), "q11": ("ring", "mcp"),
    "q12": ("pinky", "dip"), "q13": ("pinky", "pip"), "q14": ("pinky", "mcp"),
    "q15": ("thumb", "cmc"),
}
# u1 thumb flexion, u2..u5 index..pinky, u6 thumb CMC
SERVO_OF = {"thumb": {"ip": "u1", "mp": "u1", "cmc": "u6"}, "index": "u2", "middle": "u3", "ring": "u4",
            "pinky": "u5"}


def test_joints_follow_table_one():
    assert len(T.JOINTS) == 15 and T.N_JOINTS == 15
    for j in T.JOINTS:
        assert TABLE_I[j.label] == (j.digit, j.key)
        assert j.index == int(j.label[1:]) - 1
        want = SERVO_OF[j.digit] if j.digit != "thumb" else SERVO_OF["thumb"][j.key]
        assert T.SERVOS[j.servo].label == want


def test_servos_and_labels():
    assert [s.label for s in T.SERVOS] == ["u1", "u2", "u3", "u4", "u5", "u6"]
    assert [s.link for s in T.SERVOS] == [f"servo_pulley_{k}" for k in (1, 2, 3, 4, 5, 6)]
    assert [s.title for s in T.SERVOS] == [f"servo {k}" for k in (1, 2, 3, 4, 5, 6)]
    assert T.CMC_SERVO == 5 and T.CMC_Q == 14
    assert T.U_COLUMNS[T.TENDON_SERVOS] == ("u1", "u2", "u3", "u4", "u5")


@pytest.mark.parametrize("digit, keys, q_index", [
    ("thumb", ("mp", "ip"), (1, 0)),
    ("index", ("mcp", "pip", "dip"), (4, 3, 2)),
    ("pinky", ("mcp", "pip", "dip"), (13, 12, 11)),
])
def test_chains_reference_joint_first(digit, keys, q_index):
    c = T.chain(digit)
    assert c.keys == keys and c.q_index == q_index
    assert all(T.JOINTS[i].reference == f"{digit}_{keys[0]}" for i in q_index)


def test_link_tree():
    parent = {ln.name: ln.parent for ln in T.LINKS}
    assert parent["palm"] is None
    assert parent["index_base"] == "palm" and parent["index_distal"] == "index_middle"
    assert parent["thumb_cmc_base"] == "palm" and parent["thumb_distal"] == "thumb_proximal"
    # every servo sits in the forearm module, fixed to the palm behind the wrist; the CMC pulley on
    # the CMC base (servo 6 turns it through the loop)
    assert parent["forearm"] == "palm"
    assert all(parent[f"servo_pulley_{k}"] == "forearm" for k in range(1, 7))
    assert parent["thumb_cmc_pulley"] == "thumb_cmc_base"
    assert len(T.LINKS) == 1 + 1 + 4 * 4 + 3 + 1 + 6
    # parents come before their children: a writer can walk the tuple in order
    seen = set()
    for ln in T.LINKS:
        assert ln.parent is None or ln.parent in seen
        seen.add(ln.name)
    for j in T.JOINTS:
        assert T.link(j.child).parent == j.parent and T.link(j.child).parent_joint == j.name


def test_tendons():
    kinds = {}
    for t in T.TENDONS:
        kinds.setdefault(t.kind, []).append(t.name)
    # per digit one drive and one return; a coupling loop per pair of adjacent chain joints (4 x 2 + 1)
    assert len(kinds["drive"]) == 5 and len(kinds["return"]) == 5 and len(kinds["coupling"]) == 9
    # and the CMC's loop from servo 6's pulley to the CMC pulley
    (loop6,) = (t for t in T.TENDONS if t.kind == "loop")
    assert loop6.servo == T.CMC_SERVO and loop6.joints == ("thumb_cmc",)
    assert loop6.links[0] == "servo_pulley_6" and loop6.links[-1] == "thumb_cmc_pulley"
    loop = next(t for t in T.TENDONS if t.name == "index_mcp_pip")
    assert loop.links == ("index_base", "index_proximal", "index_middle")
