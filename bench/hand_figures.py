"""Pictures of the assembled hand (docs/parts.md, README, docs/assembly.md, docs/opposition.md): the default
hand's built solids placed by ``assembly.pose_transforms`` at rest (two views), at 60 % of every joint limit,
in the power grasp (every tendon servo at the end of its travel, the CMC at rest) with each fingertip's
distance to the palm measured on the solids, closed on a 35 mm cylinder across the palm
(``cad.grasp.power_grasp``) and holding it palm down in MuJoCo (``export.hold``), where the thumb's pad comes within 1 mm of the index, middle
and ring pads on the solids (``cad.grasp.solid_contact``), and exploded (each part moved off the one it
mounts on, along the way it goes on). Run from the repository's root:
.venv/bin/python bench/hand_figures.py [OUT_DIR]   (default docs/img; about a minute)
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from phantom_cad import make_hand, units
from phantom_cad.cad import assembly, grasp, measure, registry
from phantom_cad.export import render, step_stl
from phantom_cad.export.hold import hold_cylinder
from phantom_cad.export.pipeline import build_hand
from phantom_cad.kinematics import link_frames
from phantom_cad.kinematics import opposition
from phantom_cad.kinematics import thenar
from phantom_cad.kinematics.topology import CMC_PULLEY, CMC_Q, CMC_SERVO, FINGERS, JOINTS, SERVOS, digit_links, link
from phantom_cad.params.io import DEFAULT_PARAMS, load_params


#: the power grasp's cylinder across the palm (mm): the paper's 35 mm on its 189 mm hand, the default
CYLINDER_MM = 35.0
#: how far (mm) each level of an exploded digit moves along the digit, the forearm module back from the
#: wrist, the servo pulleys up off their servos
EXPLODE_DIGIT, EXPLODE_FOREARM, EXPLODE_PULLEY = 28.0, 45.0, 28.0


def exploded(T: dict, cmc_drop: float) -> dict:
    """{link: offset (mm, palm frame)}: each part moves with the one it mounts on, and further off it
    along the way it goes on: a finger's links along its first link's y (the finger base off its
    socket, each phalanx off the one before), the thumb's CMC base ``cmc_drop`` down its CMC axis
    (its column out of the palm's journal) and its phalanges along its arm, the CMC pulley out of the
    palm's cavity the way it slides in (in its plane, toward the CMC servo's pulley), the forearm
    module back from the wrist, a servo pulley up its shaft. ``T`` in topology order (parents
    first)."""
    base, servo_pulley = JOINTS[CMC_Q].child, SERVOS[CMC_SERVO].link
    out = {}
    for name in T:
        ln = link(name)
        if ln.parent is None:
            out[name] = np.zeros(3)
        elif ln.segment == "servo_pulley":
            out[name] = out[ln.parent] + EXPLODE_PULLEY * T[name][:3, 2]
        elif name == base:
            out[name] = out[ln.parent] - cmc_drop * T[name][:3, 2]
        elif name == CMC_PULLEY:          # in the palm's cavity, not on the dropped CMC base
            axis = T[name][:3, 2]
            way = T[servo_pulley][:3, 3] - T[name][:3, 3]
            way -= (way @ axis) * axis
            out[name] = out[link(base).parent] + EXPLODE_PULLEY * way / np.linalg.norm(way)
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
    limits = {j["name"]: j["limits"] for j in link_frames.joints(p)}
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
    # the CMC base drops its column's length and a digit step below the palm's palmar face
    shift = exploded(T, units.mm(thenar.thenar(p)["top"]) + EXPLODE_DIGIT)
    items = []
    for name, (v, f, color, digit) in meshes.items():
        label = name if (digit is None and not name.startswith("servo_pulley_")) or name.endswith("_base") else None
        items.append(render.MeshItem(name, v @ T[name][:3, :3].T + T[name][:3, 3] + shift[name], f, tuple(color),
                                     label))
    render.render_png(items, out / "hand_exploded.png", title=f"{p.name} hand ({p.side}), exploded",
                      subtitle="each part moved off the one it mounts on, along the way it goes on (docs/assembly.md)",
                      elev=50.0, azim=-150.0, size_px=1100)
    print(f"wrote {out / 'hand_exploded.png'}")


def _items(meshes, T, named=()):
    """The meshes placed by ``T``, each digit labelled (once, over what shows of its parts), and
    the parts in ``named``."""
    return [render.MeshItem(name, v @ T[name][:3, :3].T + T[name][:3, 3], f, tuple(color),
                            digit or (name if name in named else None))
            for name, (v, f, color, digit) in meshes.items()]


def postures(p, meshes, solids, out: Path) -> None:
    """The power grasp and the thumb's closest approach to each opposed fingertip, on the solids."""
    h = make_hand(p, compensation="paper")     # as the power grasp's tests (tests/conftest.py)
    cmc = next(s.index for s in SERVOS if s.drive == "loop")
    # the hand without its forearm module and servo pulleys: the grasp pictures' close views
    hand_only = {n: m for n, m in meshes.items() if n != "forearm" and not n.startswith("servo_pulley_")}
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
    # the 35 mm cylinder laid against the palm's heel at first contact (cad.grasp.power_grasp: every finger
    # touches it past its equator, the thumb out of the way; pressing on, MuJoCo's fingers hold it against
    # the heel, palm down: docs/parts.md)
    g, _ = grasp.power_grasp(h, solids, CYLINDER_MM)
    if g is None:
        sys.exit(f"error: the four fingers do not all reach past the equator of a {CYLINDER_MM} mm cylinder laid against "
                 "the heel")
    T = assembly.pose_transforms(p, h.forward(g.u, compensated=True))
    cv, cf = step_stl.tessellate(g.solid(), 0.05)
    cylinder = render.MeshItem("cylinder", cv, cf, (0.85, 0.85, 0.80), f"{CYLINDER_MM:g} mm cylinder")
    wraps = ", ".join(f"{f} {c.wrap_deg:.0f}" for f, c in g.fingers.items())
    fname = "hand_power_cylinder.png"
    with tempfile.TemporaryDirectory() as tmp:
        views = []
        shots = ((5.0, 0.0, "seen from the ulnar side",
                  f"each finger flexed until 1 mm from it; wrap (deg, 90 = its distal side): {wraps}"),
                 (-35.0, 45.0, "from the palm's distal, ulnar side",
                  f"commands {', '.join(f'{x:.0f}' for x in np.degrees(g.u))} deg; pressing on, they hold it against "
                  "the palm's heel (MuJoCo, palm down)"))
        for i, (elev, azim, what, sub) in enumerate(shots):
            views.append(Path(tmp) / f"{i}.png")
            render.render_png(_tips_labelled(hand_only, T, FINGERS) + [cylinder], views[-1],
                              title=f"first contact on a {CYLINDER_MM:g} mm cylinder, {what}",
                              subtitle=sub, elev=elev, azim=azim, size_px=800)
        _side_by_side(views[0], views[1], out / fname)
    print(f"wrote {out / fname}: axis at y {g.axis_y_mm:.1f} mm, wraps {wraps}")
    # pressing on, in MuJoCo (export.hold, on the default hand's exported MJCF, as tests/export/test_mjcf.py):
    # the fingers closed to the end of their travel, then the palm facing down (gravity toward its palmar side)
    with tempfile.TemporaryDirectory() as tmp:
        result = build_hand(None, Path(tmp) / "export", slice=None)
        held = hold_cylinder(result.out_dir / "description" / "mjcf" / "scene.xml", g)
    T = assembly.pose_transforms(p, held.q)
    M = held.T_cylinder @ np.linalg.inv(held.T_start)
    cylinder = render.MeshItem("cylinder", cv @ M[:3, :3].T + M[:3, 3], cf, (0.85, 0.85, 0.80),
                               f"{CYLINDER_MM:g} mm cylinder, {held.mass_kg * 1e3:.0f} g")
    fname = "hand_power_held.png"
    render.render_png(_tips_labelled(hand_only, T, FINGERS) + [cylinder], out / fname,
                      title=f"held in MuJoCo, palm down: the {CYLINDER_MM:g} mm cylinder after 2 s of closing and 3 s of gravity",
                      subtitle=f"gravity toward the palmar side (down here); let go in the closed hand, moved "
                      f"{held.released_mm:.1f} mm, then {held.moved_mm:.1f} mm palm down; seen from the ulnar side",
                      elev=5.0, azim=0.0, size_px=1000)
    print(f"wrote {out / fname}: let go, moved {held.released_mm:.1f} mm, then {held.moved_mm:.1f} mm palm down, "
          f"servo torques {held.servo_torques.round(3).tolist()} N m")
    # opposition: the commands where the thumb's pad comes within 1 mm of each opposed fingertip's pad on
    # the solids (cad.grasp.solid_contact: the model's contacts, squarest first, the finger flexed onto
    # the still thumb), seen square to the line between the closest points, whole and close up
    for f in opposition.OPPOSED:
        c = grasp.solid_contact(h, solids, f)
        if c is None:
            sys.exit(f"error: the thumb's pad does not reach the {f}'s on the solids (cad.grasp)")
        T = assembly.pose_transforms(p, h.forward(c.u, compensated=True))
        elev, azim = _square_to(c, T)
        fname = f"hand_opposition_{f}.png"
        cmd = ", ".join(f"{x:.1f}" for x in np.degrees(c.u))
        with tempfile.TemporaryDirectory() as tmp:
            whole, near = Path(tmp) / "whole.png", Path(tmp) / "near.png"
            render.render_png(_tips_labelled(hand_only, T, ("thumb", f)), whole,
                              title=f"{p.name} hand ({p.side}): the thumb's pad on the {f} pad",
                              subtitle=f"servo commands {cmd} deg (u1..u6), seen square to the contact; "
                              "the forearm module left out",
                              elev=elev, azim=azim, size_px=800)
            close = {n: m for n, m in meshes.items() if n in (f"{f}_distal", f"{f}_middle", "thumb_distal")}
            render.render_png(_tips_labelled(close, T, ("thumb", f)), near,
                              title="close up: the two fingertips",
                              subtitle=f"{c.distance_mm:.2f} mm apart on the solids (OpenCascade), pad to pad",
                              elev=elev, azim=azim, size_px=800)
            _side_by_side(whole, near, out / fname)
        print(f"wrote {out / fname}: {c.distance_mm:.3f} mm at {cmd} deg")


def _tips_labelled(meshes, T, digits):
    """The meshes placed by ``T``, the distal phalanges of ``digits`` labelled with their digit."""
    return [render.MeshItem(name, v @ T[name][:3, :3].T + T[name][:3, 3], f, tuple(color),
                            digit if digit in digits and name == f"{digit}_distal" else None)
            for name, (v, f, color, digit) in meshes.items()]


def _square_to(c, T) -> tuple[float, float]:
    """(elev, azim) deg of a view square to the contact's line (thumb point to finger point), from
    the palmar, radial and distal side as far as that allows: the gap shows as a sliver between
    the two tips, the other fingers behind them."""
    n = c.finger_point - c.thumb_point
    n = n / np.linalg.norm(n)
    radial = np.sign(T["thumb_cmc_base"][0, 3] - T["middle_base"][0, 3])
    want = np.array([radial, 0.4, -1.0])
    v = want - (want @ n) * n
    v = v / np.linalg.norm(v)
    return float(np.degrees(np.arcsin(v[2]))), float(np.degrees(np.arctan2(v[1], v[0])))


def _side_by_side(left: Path, right: Path, out: Path) -> None:
    from PIL import Image

    a, b = Image.open(left), Image.open(right)
    both = Image.new("RGB", (a.width + b.width, max(a.height, b.height)), "white")
    both.paste(a.convert("RGB"), (0, 0))
    both.paste(b.convert("RGB"), (a.width, 0))
    both.save(out, optimize=True)

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "img")
