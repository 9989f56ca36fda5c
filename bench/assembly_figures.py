"""Pictures of the threading steps (docs/assembly.md), rendered from the model: the index finger
and the thumb of the default hand (right hand) at rest (u = 0, every joint 0), one figure per step
(the finger's PIP-DIP loop, MCP-PIP loop, return cord and drive; the thumb's MP-IP loop, return
cord and drive). Run from the repository's root:
.venv/bin/python bench/assembly_figures.py [OUT_DIR]   (default docs/img)

The parts are the real built solids (``cad.registry.part(params, name).build()``, right-handed,
in their link frames, mm), tessellated (``export.step_stl.tessellate``) and placed with the
routing model's rest transforms (``routing_paths.pose``: T_palm_link, metres); everything is drawn in
the digit's first link's frame (the index base, the thumb's CMC base: x ulnar, y along the digit,
z dorsal; mm), in two views:

* side: seen from the ulnar side (+x), y to the right, z up;
* top: seen from the dorsal side (+z), y to the right, x (ulnar) down.

The parts are light grey shaded silhouettes (Lambert shading, painter's order, back faces
culled); the tendons (``routing.routes`` / ``routing_paths.strand_path``) are drawn on top of them, as
if the parts were glass: the step's tendon in colour, the others faint. The anchors are the
routing model's strand ends, with their roles read from ``cad.parts.tendons.link_tendons`` (hub
clamp: M2 set screw; groove clamp: knot pocket; knot: knot well); the drive's are its servo
pulley clamp and its knot behind G2 (``routing`` Point anchors). For the finger's drive the servo
pulley (``servo_pulley_2``) is drawn too; the palm is not (its channel is the straight run from the
pulley to the finger base's entry). The thumb's drive turns in the palm above the CMC pulley and comes down the CMC
axis through the column into the CMC base; the panels show it from there (its palm path is in docs/transmission.md).
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from phantom_cad.cad import registry  # noqa: E402
from phantom_cad.cad.parts.tendons import link_tendons  # noqa: E402
from phantom_cad.export.step_stl import tessellate  # noqa: E402
from phantom_cad.kinematics import couplers
from phantom_cad.kinematics import routing  # noqa: E402
from phantom_cad.kinematics import routing_paths
from phantom_cad.kinematics.topology import SERVOS, chain, digit_links  # noqa: E402
from phantom_cad.params.io import DEFAULT_PARAMS, load_params  # noqa: E402

#: chord tolerance of the pictures' tessellation (mm)
TESSELLATION_MM = 0.1

COLOURS = {"drive": "#d62728", "a": "#ff7f0e", "b": "#2ca02c", "return": "#1f77b4"}
STRAND_LABEL = {"drive": "drive", "a": "loop strand a", "b": "loop strand b", "return": "return cord"}

#: digit -> (what it is called, whether its servo pulley is drawn, ((doc step, file, tendon, title), ...));
#: its parts are the digit's links (``topology.digit_links``), its frame the first of them
DIGITS = {
    "index": ("index finger", True, (
        (2, "assembly_pip_dip.png", "index_pip_dip", "PIP-DIP loop"),
        (3, "assembly_mcp_pip.png", "index_mcp_pip", "MCP-PIP loop"),
        (4, "assembly_return.png", "index_return", "return cord"),
        (5, "assembly_drive.png", "index_drive", "drive"))),
    "thumb": ("thumb", False, (
        (2, "assembly_thumb_mp_ip.png", "thumb_mp_ip", "MP-IP loop"),
        (4, "assembly_thumb_return.png", "thumb_return", "return cord"),
        (5, "assembly_thumb_drive.png", "thumb_drive", "drive"))),
}

#: what the maker does at an anchor, by its role (cad.parts.tendons.Anchor.role or the drive's)
DOES = {
    "hub clamp": ("hub clamp: both ends round the hub,\none each way; pull taut, tighten\n"
                  "the M2 set screw (cheek's outer face)"),
    "groove clamp": ("knot pocket: the cord's middle,\noverhand-knotted, seated here;\n"
                     "one end each way round the groove"),
    "knot": "knot well (dorsal face):\nknot the elastic cord here",
    "servo clamp": "servo pulley's anchor hole:\nknot the drive, wind as the BOM says",
    "guide G2": "G2, then knot the drive\nin the well behind G2",
}


def _h(P: np.ndarray) -> np.ndarray:
    return np.c_[P, np.ones(len(P))]


def _to_mm(T: np.ndarray) -> np.ndarray:
    """A transform in metres as one in millimetres."""
    out = T.copy()
    out[:3, 3] *= 1e3
    return out


class Scene:
    """The parts' meshes and the tendons' paths at rest, in the digit's first link's frame (mm)."""

    def __init__(self, p, digit: str, parts):
        self.p, self.digit, self.frame = p, digit, parts[0]
        u = np.zeros(len(SERVOS))
        self.Ts = routing_paths.pose(p, None, u)
        self.inv = np.linalg.inv(self.Ts[self.frame])
        self.meshes, self.T_mm = {}, {}
        for name in parts:
            v, f = tessellate(registry.part(p, name).build(), TESSELLATION_MM)   # link frame, mm
            T = _to_mm(self.inv @ self.Ts[name])                                  # base <- link, mm
            self.T_mm[name] = T
            self.meshes[name] = ((_h(v) @ T.T)[:, :3], f)
        self.routes = [r for r in routing.routes(p) if r.tendon.digit == digit]
        self.paths = {}
        for r in self.routes:
            for st in r.strands:
                _, pts = routing_paths.strand_path(p, st, self.Ts)
                self.paths[st.name] = self.base(pts)

    def base(self, P_palm_m) -> np.ndarray:
        """Points in the palm frame (m) -> the base frame (mm)."""
        return (_h(np.atleast_2d(P_palm_m)) @ self.inv.T)[:, :3] * 1e3

    def element(self, e) -> np.ndarray:
        """A routing element's position (its link frame, m) in the base frame (mm)."""
        pos = e.pos if isinstance(e, routing.Point) else e.centre
        return self.base((self.Ts[e.link] @ np.array([*pos, 1.0]))[:3])[0]


#: views: (horizontal axis, vertical axis, depth axis toward the viewer) of the base frame
VIEWS = {"side": (1, 2, 0), "top": (1, 0, 2)}


def draw_parts(ax, scene: Scene, view: str) -> None:
    h, v, d = VIEWS[view]
    light = np.zeros(3)
    light[d], light[v], light[h] = 1.0, 0.6, -0.35      # from the viewer, a little from above left
    light /= np.linalg.norm(light)
    polys, shades, depths = [], [], []
    for verts, faces in scene.meshes.values():
        tri = verts[faces]                                   # (m, 3, 3)
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        ln = np.linalg.norm(n, axis=1)
        ok = ln > 1e-12
        tri, n = tri[ok], n[ok] / ln[ok, None]
        front = n[:, d] > 0                                  # back faces culled
        tri, n = tri[front], n[front]
        polys.append(tri[:, :, [h, v]])
        shades.append(0.62 + 0.32 * np.clip(n @ light, 0.0, 1.0))
        depths.append(tri[:, :, d].mean(axis=1))
    polys, shades, depths = np.concatenate(polys), np.concatenate(shades), np.concatenate(depths)
    order = np.argsort(depths)
    col = np.repeat(shades[order, None], 3, axis=1)
    ax.add_collection(PolyCollection(polys[order], facecolors=col, edgecolors=col, linewidths=0.15,
                                     zorder=1, rasterized=True))


def section(scene: Scene, axis: int, at: float) -> list[np.ndarray]:
    """The parts' outlines where a plane cuts their meshes: segments (2, 3). The plane is
    {axis = at} for the finger's parts; a servo pulley (a disc not quite square to the finger) is
    cut in its own mid-plane for the side view (axis 0), where its drive runs."""
    segs = []
    for name, (verts, faces) in scene.meshes.items():
        n, c = np.eye(3)[axis], np.eye(3)[axis] * at
        if name.startswith("servo_pulley") and axis == 0:
            n, c = scene.T_mm[name][:3, 2], scene.T_mm[name][:3, 3]
        tri = verts[faces]
        s = (tri - c) @ n - 1e-5                              # off any vertex lying in the plane
        cut = (s.min(axis=1) < 0) & (s.max(axis=1) > 0)
        tri, s = tri[cut], s[cut]
        pts = []
        for i, j in ((0, 1), (1, 2), (2, 0)):
            a, b, sa, sb = tri[:, i], tri[:, j], s[:, i], s[:, j]
            t = np.where(sa * sb < 0, sa / np.where(sa == sb, 1.0, sa - sb), np.nan)
            pts.append(a + t[:, None] * (b - a))
        pts = np.stack(pts, axis=1)                          # (m, 3 edges, 3)
        for P in pts:
            P = P[~np.isnan(P[:, 0])]
            if len(P) == 2:
                segs.append(P)
    return segs


def draw_section(ax, scene: Scene, view: str, at: float) -> None:
    h, v, d = VIEWS[view]
    segs = [S[:, [h, v]] for S in section(scene, d, at)]
    ax.add_collection(LineCollection(segs, colors="0.25", linewidths=0.7, zorder=2))


def _key(r, st) -> str:
    return r.tendon.kind if r.tendon.kind != "coupling" else st.name[-1]


def draw_tendons(ax, scene: Scene, view: str, tendon: str) -> None:
    h, v, _ = VIEWS[view]
    for r in scene.routes:
        for st in r.strands:
            xy = scene.paths[st.name][:, [h, v]]
            k = _key(r, st)
            if r.name == tendon:
                ax.plot(xy[:, 0], xy[:, 1], color=COLOURS[k], lw=1.7, zorder=4,
                        label=STRAND_LABEL[k] if k not in ("drive", "return") else f"{r.name}")
            else:
                ax.plot(xy[:, 0], xy[:, 1], color="0.35", lw=0.6, alpha=0.45, zorder=3,
                        label="the other tendons (faint)")


def _joint(e) -> str:
    return e.joint.split("_", 1)[1].upper()


def marks(scene: Scene, tendon: str) -> list[tuple[np.ndarray, str | None, str]]:
    """(position mm, label or None, marker) of where the step's tendon is anchored and led."""
    r = next(r for r in scene.routes if r.name == tendon)
    out, seen = [], set()
    for st in r.strands:
        els = st.elements
        for i, e in enumerate(els):
            key = (e.link, tuple(np.round(e.pos if isinstance(e, routing.Point) else e.centre, 7)), e.role)
            if key in seen:
                continue
            seen.add(key)
            P = scene.element(e)
            if isinstance(e, routing.Point) and e.kind == "anchor":
                nb = els[i + 1 if i == 0 else i - 1]
                if e.role == "clamp" and isinstance(nb, routing.Pulley) and nb.role == "servo":
                    role = "servo clamp"
                elif e.role == "guide G2":
                    role = "guide G2"
                else:    # the part's own anchor feature, found where the routing model puts it
                    lt = link_tendons(scene.p, e.link)
                    mm = np.asarray(e.pos) * 1e3
                    role = next(a.role for a in lt.anchors if np.linalg.norm(a.pos - mm) < 1e-6)
                where = e.link
                if isinstance(nb, routing.Pulley) and nb.role in ("hub", "groove"):
                    side = "ulnar" if nb.centre[0] > 0 else "radial"
                    where += (f", {_joint(nb)} clevis hub ({side} cheek)" if nb.role == "hub"
                              else f", {_joint(nb)} tongue groove ({side})")
                out.append((P, f"{where}:\n{DOES[role]}", "o"))
            elif isinstance(e, routing.Point) and e.role == "crossing":
                out.append((P, f"{e.link}: the ends cross once\n(its two crossing channels)", "X"))
            elif isinstance(e, routing.Point) and e.role == "interface" and scene.digit in couplers.couplers(scene.p):
                # the drive's split: the crimp stop at rest in the palm's bore, the loop behind it
                cp = couplers.couplers(scene.p)[scene.digit]
                back = scene.base(routing_paths.strand_nodes(st, scene.Ts)[i - 1][1])[0]
                u = (back - P) / np.linalg.norm(back - P)
                mid = (cp.bearing - scene.p.hardware.stop_length / 2.0) * 1e3
                out.append((P + mid * u, "palm bore: the crimp stop, the finger\nstrand's loop hooked behind it", "D"))
                out.append((P, f"{e.link}: entry channel\n(the split: docs/transmission.md)", "s"))
            elif isinstance(e, routing.Point) and e.role in ("interface", "guide G1"):
                entry = ("down the CMC axis\n(through the column)" if scene.digit == "thumb"
                         else "entry channel\n(from the palm channel)")
                what = {"interface": entry, "guide G1": "through G1"}[e.role]
                out.append((P, f"{e.link}: {what}", "s"))
            elif isinstance(e, routing.Pulley) and e.role == "return":
                out.append((P, f"{e.link}: over the {_joint(e)}\nreturn groove (dorsal)", "+"))
            elif isinstance(e, routing.Pulley):
                out.append((P, None, "+"))
    return out


def draw_marks(ax, scene: Scene, view: str, tendon: str, labelled: bool) -> None:
    """The marks; labelled: their labels spread over the panel, alternately above and below."""
    h, v, _ = VIEWS[view]
    ms = marks(scene, tendon)
    for P, _, m in ms:
        ax.plot(P[h], P[v], m, ms=6 if m != "+" else 9, mfc="white" if m in ("o", "D") else "k", mec="k",
                mew=1.2, zorder=6)
    if not labelled:
        return
    lab = sorted((m for m in ms if m[1]), key=lambda m: m[0][h])
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    W = 0.24 * (x1 - x0)                   # a label's width, about
    for up in (True, False):
        mine = lab[0 if up else 1::2]
        xs = [float(P[h]) for P, _, _ in mine]
        for _ in range(2):                  # each over its mark, pushed apart, kept in the panel
            for k in range(1, len(xs)):
                xs[k] = max(xs[k], xs[k - 1] + W)
            over = xs[-1] - (x1 - W / 2) if xs else 0.0
            xs = [x - max(over, 0.0) for x in xs]
            if xs:
                xs[0] = max(xs[0], x0 + W / 2)
        ty = y1 - 0.04 * (y1 - y0) if up else y0 + 0.04 * (y1 - y0)
        for tx, (P, text, _) in zip(xs, mine):
            ax.annotate(text, (P[h], P[v]), xytext=(tx, ty), fontsize=6.5, ha="center",
                        va="top" if up else "bottom", zorder=7,
                        arrowprops=dict(arrowstyle="-", color="0.2", lw=0.6, shrinkA=0, shrinkB=4),
                        bbox=dict(boxstyle="round,pad=0.25", fc="white", ec="0.6", lw=0.5, alpha=0.92))


def figure(scene: Scene, step: int, tendon: str, title: str, out: Path, what: str) -> None:
    r = next(r for r in scene.routes if r.name == tendon)
    allpts = np.concatenate([m[0] for m in scene.meshes.values()])
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    # the section planes: the tendon's own plane (side view), the joints' axes' plane (top view)
    x_t = float(np.round(scene.paths[r.strands[0].name][-1, 0], 2))     # at its last anchor
    planes = {"side": x_t, "top": 0.0}
    lims = {"side": (-24.0, 24.0), "top": (13.0, -13.0)}
    if r.tendon.kind == "coupling":
        where = f"the loop runs in the {'ulnar' if x_t > 0 else 'radial'} half of the slot (x = {x_t:.2f} mm)"
    elif r.tendon.kind == "return":
        where = f"the return cord runs at x = {x_t:.2f} mm, on the dorsal side"
    else:
        where = "the drive runs in the mid-plane (x = 0), palmar (the palm around its channel is not drawn)"
    fig, axes = plt.subplots(2, 1, figsize=(10.5, 8.4), gridspec_kw={"height_ratios": (48, 26)},
                             layout="constrained")
    for ax, view in zip(axes, ("side", "top")):
        h, v, _ = VIEWS[view]
        draw_parts(ax, scene, view)
        draw_section(ax, scene, view, planes[view])
        draw_tendons(ax, scene, view, tendon)
        ax.set_xlim(lo[h] - 3, hi[h] + 3)
        ax.set_ylim(*lims[view])
        draw_marks(ax, scene, view, tendon, labelled=view == "side")
        if view == "side":
            for name, (verts, _) in scene.meshes.items():     # which part is which
                y0, y1 = verts[:, 1].min(), verts[:, 1].max()
                ax.text((y0 + y1) / 2, verts[:, 2].min() - 1.0, name, fontsize=6.5, style="italic",
                        ha="center", va="top", color="0.3", zorder=5)
            ax.set_title("side, seen from the ulnar side: the parts as glass, outlined where the tendon's "
                         f"plane x = {planes[view]:.2f} mm cuts them", fontsize=9)
            ax.set_ylabel("z dorsal (mm)", fontsize=8)
        else:
            ax.set_title(f"top, seen from the dorsal side (radial above, ulnar below): {where};\n"
                         "the parts outlined where the joints' axes' plane z = 0 cuts them", fontsize=8.5)
            ax.set_ylabel("x ulnar (mm)", fontsize=8)
            ax.text(0.005, 0.97, "radial", transform=ax.transAxes, fontsize=8, va="top", color="0.2")
            ax.text(0.005, 0.03, "ulnar", transform=ax.transAxes, fontsize=8, va="bottom", color="0.2")
        ax.set_xlabel(f"y along the {'thumb' if scene.digit == 'thumb' else 'finger'}, {scene.frame} frame (mm)",
                      fontsize=8)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=7)
        ax.grid(lw=0.3, alpha=0.4)
    fig.suptitle(f"Step {step}: {title} ({tendon}, {r.diameter * 1e3:.1f} mm cord), {what} at rest",
                 fontsize=11)
    fig.get_layout_engine().set(h_pad=0.08, hspace=0.04)
    handles, labels = axes[0].get_legend_handles_labels()
    seen = {k: hd for k, hd in zip(labels, handles) if not k.startswith("section")}
    seen["section outline (parts cut by the plane)"] = Line2D([], [], color="0.25", lw=0.7)
    ms = {m for _, _, m in marks(scene, tendon)}
    seen["anchor (knot / clamp)"] = Line2D([], [], ls="", marker="o", mfc="white", mec="k")
    if "+" in ms:
        seen["pulley centre"] = Line2D([], [], ls="", marker="+", mec="k", ms=8)
    if "X" in ms:
        seen["crossing"] = Line2D([], [], ls="", marker="X", mfc="k", mec="k")
    if "s" in ms:
        seen["via (entry, G1)"] = Line2D([], [], ls="", marker="s", mfc="k", mec="k")
    if "D" in ms:
        seen["crimp stop (the drive's split)"] = Line2D([], [], ls="", marker="D", mfc="white", mec="k")
    fig.legend(seen.values(), seen.keys(), fontsize=7, loc="outside lower center", ncol=4, framealpha=0.9)
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main(out: Path) -> None:
    p = load_params(DEFAULT_PARAMS)
    out.mkdir(parents=True, exist_ok=True)
    for digit, (what, with_pulley, steps) in DIGITS.items():
        parts = tuple(ln.name for ln in digit_links(digit))
        pulley = SERVOS[chain(digit).servo].link
        scene = Scene(p, digit, parts + ((pulley,) if with_pulley else ()))
        drive_meshes = scene.meshes
        digit_meshes = {n: m for n, m in drive_meshes.items() if n != pulley}
        for step, name, tendon, title in steps:
            scene.meshes = drive_meshes if tendon.endswith("_drive") else digit_meshes
            figure(scene, step, tendon, title, out / name, what)
            print(out / name)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "img")
