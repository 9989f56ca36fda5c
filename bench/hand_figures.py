"""Pictures of the assembled hand (docs/parts.md, README, docs/assembly.md, docs/opposition.md): the default
hand's built solids placed by ``assembly.pose_transforms`` at rest (two views), at 60 % of every joint limit,
in the power grasp (every tendon servo at the end of its travel, the CMC at rest) with each fingertip's
distance to the palm measured on the solids, at the thumb's closest approach to the index, middle and ring
pads (``kinematics.opposition.reach`` of the file's thumb), and exploded (each part moved off the one it
mounts on, along the way it goes on). Run from the repository's root:
.venv/bin/python bench/hand_figures.py [OUT_DIR]   (default docs/img; about a minute)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from phantom_cad import make_hand
from phantom_cad.cad import assembly, measure, registry
from phantom_cad.export import render, step_stl
from phantom_cad.kinematics import frames, opposition
from phantom_cad.kinematics.topology import FINGERS, JOINTS, N_SERVOS, SERVOS, chain, digit_links, link
from phantom_cad.params.io import DEFAULT_PARAMS, load_params


#: how far (mm) each level of an exploded digit moves along the digit, the forearm module back from the
#: wrist, the servo pulleys up off their servos
EXPLODE_DIGIT, EXPLODE_FOREARM, EXPLODE_PULLEY = 28.0, 45.0, 28.0


def exploded(T: dict) -> dict:
    """{link: offset (mm, palm frame)}: each part moves with the one it mounts on, and further off it
    along the way it goes on: a digit's links along its first link's y (the finger base off its socket,
    each phalanx off the one before), the forearm module back from the wrist, a servo pulley up its
    shaft. ``T`` in topology order (parents first)."""
    out = {}
    for name in T:
        ln = link(name)
        if ln.parent is None:
            out[name] = np.zeros(3)
        elif ln.segment == "servo_pulley":
            out[name] = out[ln.parent] + EXPLODE_PULLEY * T[name][:3, 2]
        elif ln.digit is None:
            out[name] = out[ln.parent] + np.array([0.0, -EXPLODE_FOREARM, 0.0])
        else:
            out[name] = out[ln.parent] + EXPLODE_DIGIT * T[digit_links(ln.digit)[0].name][:3, 1]
    return out


def main(out: Path) -> None:
    p = load_params(DEFAULT_PARAMS)
    meshes, solids = {}, {}
    for name in assembly.part_names(p):
        part = registry.part(p, name)
        solids[name] = part.build()
        v, f = step_stl.tessellate(solids[name], 0.05)
        meshes[name] = (v, f, part.color, part.digit)
    limits = {j["name"]: j["limits"] for j in frames.joints(p)}
    q60 = np.array([0.6 * limits[j.name][1] for j in JOINTS])
    out.mkdir(parents=True, exist_ok=True)
    shots = (("hand_rest.png", None, "rest pose", (28.0, -62.0)),
             ("hand_top.png", None, "rest pose, seen from the dorsal side", (90.0, -90.0)),
             ("hand_flexed.png", q60, "60 % of every joint limit, seen from the palm side", (-25.0, -125.0)))
    for fname, q, what, (elev, azim) in shots:
        T = assembly.pose_transforms(p, q)
        render.render_png(_items(meshes, T, named=("palm", "forearm")), out / fname, title=f"{p.name} hand ({p.side}), {what}",
                          subtitle="six servos in the forearm module; the thenar holds the CMC's column; default parameters", elev=elev, azim=azim,
                          size_px=1000)
        print(f"wrote {out / fname}")
    postures(p, meshes, solids, out)
    T = assembly.pose_transforms(p)
    shift = exploded(T)
    items = []
    for name, (v, f, color, digit) in meshes.items():
        label = name if (digit is None and not name.startswith("servo_pulley_")) or name.endswith("_base") else None
        items.append(render.MeshItem(name, v @ T[name][:3, :3].T + T[name][:3, 3] + shift[name], f, tuple(color),
                                     label))
    render.render_png(items, out / "hand_exploded.png", title=f"{p.name} hand ({p.side}), exploded",
                      subtitle="each part moved off the one it mounts on, along the way it goes on (docs/assembly.md)",
                      elev=62.0, azim=-75.0, size_px=1100)
    print(f"wrote {out / 'hand_exploded.png'}")


def _items(meshes, T, named=()):
    """The meshes placed by ``T``, each digit labelled once, and the parts in ``named``."""
    items, labelled = [], set()
    for name, (v, f, color, digit) in meshes.items():
        key = digit or name
        label = key if key not in labelled and (digit is not None or name in named) else None
        labelled.add(key)
        items.append(render.MeshItem(name, v @ T[name][:3, :3].T + T[name][:3, 3], f, tuple(color), label))
    return items


def postures(p, meshes, solids, out: Path) -> None:
    """The power grasp and the thumb's closest approach to each opposed fingertip, on the solids."""
    h = make_hand(p)
    cmc = next(s.index for s in SERVOS if s.drive == "loop")
    # power grasp: every tendon servo at the end of its travel, the CMC at rest
    u = np.array(h.u_max, float)
    u[cmc] = 0.0
    T = assembly.pose_transforms(p, h.forward(u))
    gaps = []
    for f in FINGERS:
        tip = measure.placed(solids[f"{f}_distal"], T[f"{f}_distal"])
        gaps.append(f"{f} {tip.distance_to(solids['palm']):.1f}")
    render.render_png(_items(meshes, T), out / "hand_power.png",
                      title=f"{p.name} hand ({p.side}), power grasp: every tendon servo at full travel, seen from the ulnar side",
                      subtitle="fingertip to palm (mm, on the solids): " + ", ".join(gaps)
                      + "; target 10 mm (docs/parts.md, known gaps)",
                      elev=5.0, azim=0.0, size_px=1000)
    print(f"wrote {out / 'hand_power.png'}")
    # opposition: the file's thumb where its pad meets each opposed fingertip's most squarely (the
    # capsules of kinematics.opposition over the thumb's (u1, u6) grid and the finger's travel: the
    # pairs in contact, the smallest facing angle), or at its closest where the pads never meet
    thumb = opposition.thumb_tips(h).placed(frames.thumb_cmc_placement(p.palm.thumb_cmc_offset,
                                                                        p.palm.thumb_cmc_axis))
    for f in opposition.OPPOSED:
        ft = opposition.finger_tips(h, f)
        gap, angle = opposition.contacts(thumb, ft)
        band = (gap <= 0.0) & (gap >= -opposition.CONTACT_BAND)
        pick = np.where(band, angle, np.inf) if band.any() else gap
        i, j = np.unravel_index(int(np.argmin(pick)), gap.shape)
        u = np.zeros(N_SERVOS)
        u[chain("thumb").servo], u[cmc], u[chain(f).servo] = thumb.u[i][0], thumb.u[i][1], ft.u[j, 0]
        T = assembly.pose_transforms(p, h.forward(u, compensated=True))
        a = measure.placed(solids["thumb_distal"], T["thumb_distal"])
        b = measure.placed(solids[f"{f}_distal"], T[f"{f}_distal"])
        fname = f"hand_opposition_{f}.png"
        render.render_png(_items(meshes, T), out / fname,
                          title=f"{p.name} hand ({p.side}): the thumb's pad on the {f} pad",
                          subtitle=f"thumb and {f} distal phalanges {a.distance_to(b):.1f} mm apart on the solids, "
                          "at the commands where the pads meet most "
                          "squarely (docs/opposition.md)",
                          elev=-30.0, azim=-150.0, size_px=1000)
        print(f"wrote {out / fname}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "img")
