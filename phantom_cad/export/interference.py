"""The interference checks of the assembly: pairwise intersection volumes of the placed part
meshes (manifold3d booleans), at the rest pose (:func:`interference`, every build) and over a
grid of servo commands (:func:`command_sweep`, ``phantom-cad check`` and the tests)."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from ..kinematics.topology import DIGITS, JOINTS, LINKS, SERVOS, THUMB_CHAIN, link

#: overlap volume (mm^3) above which two placed parts count as intersecting; it absorbs
#: the tessellation error (params.print.stl_tolerance) of parts that merely touch
INTERFERENCE_TOL_MM3 = 1.0


def may_touch(contacts) -> set[frozenset]:
    """The pairs of parts that may touch: every joint's parent and child, and the designed
    contacts ``contacts`` ((a, b, why) rows of the assembly's ``designed_contacts``)."""
    return {frozenset((j.parent, j.child)) for j in JOINTS} | {frozenset(c[:2]) for c in contacts}


def interference(meshes: dict[str, tuple[np.ndarray, np.ndarray]], poses: dict[str, np.ndarray],
                 allowed: set[frozenset], tol_mm3: float = INTERFERENCE_TOL_MM3) -> dict:
    """Pairwise intersection volumes of the placed meshes (manifold3d booleans).

    ``meshes`` are in link frames (mm), ``poses`` the 4x4 placements. Pairs whose boxes
    do not overlap are skipped. Returns {"checked_pairs", "collisions": [...],
    "designed_contacts": [...]} where a collision is a non-designed pair overlapping by more
    than ``tol_mm3``."""
    names = sorted(meshes)
    placed, boxes = {}, {}
    for n in names:
        v, f = meshes[n]
        T = np.asarray(poses[n], dtype=float)
        w = v @ T[:3, :3].T + T[:3, 3]
        boxes[n] = (w.min(axis=0), w.max(axis=0))
        placed[n] = (w, f)
    solids: dict[str, Any] = {}

    def solid(n):
        if n not in solids:
            solids[n] = _manifold(*placed[n])
        return solids[n]

    checked, collisions, contacts, largest = 0, [], [], None
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            (alo, ahi), (blo, bhi) = boxes[a], boxes[b]
            if np.any(alo > bhi) or np.any(blo > ahi):
                continue
            checked += 1
            vol = float((solid(a) ^ solid(b)).volume())
            designed = frozenset((a, b)) in allowed
            entry = {"parts": [a, b], "volume_mm3": round(max(vol, 0.0), 4) + 0.0}
            if designed:
                contacts.append(entry)
            else:
                if largest is None or vol > largest["volume_mm3"]:
                    largest = entry
                if vol > tol_mm3:
                    collisions.append(entry)
    return {"checked_pairs": checked, "tolerance_mm3": tol_mm3,
            "collisions": collisions, "designed_contacts": contacts,
            "largest_other_overlap": largest}


#: fractions of each servo's travel the command sweep poses the hand at (the collision check's grid)
SWEEP_FRACTIONS = (0.0, 0.25, 0.5, 0.75, 0.9, 1.0)
#: overlap volume (mm^3) above which two posed parts count as interpenetrating in the sweep: the
#: meshes' chord error (params.print.stl_tolerance) on parts that come close without touching
SWEEP_TOL_MM3 = 0.01


def _manifold(v: np.ndarray, f: np.ndarray):
    import manifold3d

    return manifold3d.Manifold(manifold3d.Mesh(vert_properties=np.asarray(v, np.float32),
                                               tri_verts=np.asarray(f, np.uint32)))


def command_sweep(meshes: dict[str, tuple[np.ndarray, np.ndarray]], hand, transforms,
                  allowed: set[frozenset], fractions=SWEEP_FRACTIONS, tol_mm3: float = SWEEP_TOL_MM3) -> dict:
    """Pairwise overlaps of the posed part meshes over a grid of servo commands (manifold3d).

    ``meshes``: {link: (vertices, faces)} in link frames (mm); ``hand``: the kinematic model
    (``forward`` maps servo angles to joint angles; ``u_min``, ``u_max`` the travel);
    ``transforms(q)``: {link: T_hand_link (mm)} at joint angles q; ``allowed``: pairs that may
    touch (a joint's parent and child, the designed contacts), never counted.

    Each servo is commanded at u_min + f (u_max - u_min) for f in ``fractions``; the thumb's two
    servos (flexion, CMC) over the grid of both. Only the digits whose parts a pair holds move:
    every digit alone (its moving parts against each other and every part that does not move
    with a servo: palm, forearm module, finger bases, servo pulleys), and every two digits
    together (the moving parts of one against those of the other). A thumb part against a finger
    part is a pinch contact, not a collision: reported with the commands where it is found.

    Returns {"poses", "checked_pairs", "tolerance_mm3", "collisions", "pinch"}: each collision
    or pinch entry is a pair with its largest overlap and the commands there (servo label ->
    fraction of the travel), and for a pinch also the smallest thumb flexion where it occurs."""
    names = sorted(meshes)
    fixed = [n for n in names if not _moves(link(n))]
    moving = {d: [ln.name for ln in LINKS if ln.digit == d and _moves(ln) and ln.name in meshes] for d in DIGITS}
    servos = {d: [s.index for s in SERVOS if s.digit == d] for d in DIGITS}
    base = {n: _manifold(*meshes[n]) for n in names}
    span = np.asarray(hand.u_max, float) - np.asarray(hand.u_min, float)
    worst: dict[tuple[str, str], dict] = {}
    poses = checked = 0

    def run(digits: tuple[str, ...], pairs: list[tuple[str, str]]) -> None:
        nonlocal poses, checked
        ss = [s for d in digits for s in servos[d]]
        for fs in itertools.product(fractions, repeat=len(ss)):
            u = np.array(hand.u_min, float)
            u[ss] += np.asarray(fs) * span[ss]
            T = transforms(hand.forward(u))
            placed: dict[str, Any] = {}

            def get(n):
                if n not in placed:
                    placed[n] = base[n].transform(np.asarray(T[n], float)[:3, :4])
                return placed[n]

            poses += 1
            for a, b in pairs:
                A, B = get(a), get(b)
                ba, bb = A.bounding_box(), B.bounding_box()
                if any(ba[i] > bb[i + 3] or bb[i] > ba[i + 3] for i in range(3)):
                    continue
                checked += 1
                vol = float((A ^ B).volume())
                key = (a, b) if a < b else (b, a)
                if vol <= tol_mm3:
                    continue
                entry = worst.setdefault(key, {"parts": list(key), "volume_mm3": 0.0})
                if vol > entry["volume_mm3"]:
                    entry["volume_mm3"] = round(vol, 4)
                    entry["commands"] = {SERVOS[s].label: float(f) for s, f in zip(ss, fs)}
                if THUMB_CHAIN.servo in ss:      # the least thumb flexion where the pair overlaps
                    f = float(fs[ss.index(THUMB_CHAIN.servo)])
                    entry["from_thumb_flexion"] = min(entry.get("from_thumb_flexion", f), f)

    def apart(pairs) -> list[tuple[str, str]]:       # the pairs that may not touch
        return [(a, b) for a, b in pairs if frozenset((a, b)) not in allowed]

    for d in DIGITS:
        run((d,), apart((a, b) for i, a in enumerate(moving[d]) for b in fixed + moving[d][i + 1:]))
    for d1, d2 in itertools.combinations(DIGITS, 2):
        run((d1, d2), apart((a, b) for a in moving[d1] for b in moving[d2]))
    digits_of = lambda e: {link(n).digit for n in e["parts"]}  # noqa: E731
    pinch = [e for e in worst.values()
             if THUMB_CHAIN.digit in digits_of(e) and len(digits_of(e) - {None}) == 2]
    collisions = [e for e in worst.values() if e not in pinch]
    for e in collisions:
        e.pop("from_thumb_flexion", None)
    order = lambda e: (-e["volume_mm3"], e["parts"])  # noqa: E731
    return {"poses": poses, "checked_pairs": checked, "tolerance_mm3": tol_mm3,
            "fractions": list(fractions), "collisions": sorted(collisions, key=order),
            "pinch": sorted(pinch, key=order)}


def _moves(ln) -> bool:
    """Whether a link moves with a servo command: it hangs below a joint of its digit."""
    while ln is not None:
        if ln.parent_joint is not None:
            return True
        ln = link(ln.parent) if ln.parent else None
    return False
