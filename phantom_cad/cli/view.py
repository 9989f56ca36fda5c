"""``phantom-cad view``: the hand in the browser, driven by the kinematic model (docs/viewer.md).

    phantom-cad view [--params P] [--out EXPORT] [--port N] [--host H]

Serves a viser scene (http://127.0.0.1:8080 by default; viser serves its own bundled client,
no network needed) with the meshes of the build's robot description package
(``EXPORT/description/urdf/<hand>.local.urdf``), six sliders for the servo commands u1..u6
over each servo's travel, an analytic / compensated toggle, the 15 joint angles and the
parameter digest. Every one of the 15 joints is set from :meth:`Hand.forward` itself, not
from the URDF's ``<mimic>`` ratios (the compensated PIP/DIP angles are not those ratios): the
viewer drops the ``<mimic>`` elements when it loads the URDF.

The export is built first (cached parts are reused) when it is missing or its manifest
records another parameter digest. :func:`start_viewer` does the work and returns a
:class:`Viewer` (server, GUI handles, the joint angles shown); the command calls it and
blocks until Ctrl-C.

viser, yourdfpy and trimesh are imported inside the functions: ``phantom-cad --help`` stays fast.
"""

from __future__ import annotations

import contextlib
import io
import sys
import threading
from pathlib import Path
from typing import Any, Callable, Optional

import typer

from .. import units
from ..errors import UserError, one_line
from ..kinematics.topology import JOINTS, SERVOS
from ..params.io import DEFAULT_PARAMS

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8080
#: slider resolution (rad): 0.057 deg, well below what a servo resolves
SLIDER_STEP = 1e-3
#: viser scene node under which every link frame hangs (flat: each link's pose is its world pose)
ROOT_NODE = "/hand"
#: decimals of the angles shown in degrees
SHOWN_DECIMALS = 4
#: initial camera (palm frame: fingers along +y, the back of the hand up +z, thumb at -x for
#: the right hand; mirrored for a left hand): direction from the hand's centre, vertical field
#: of view, distance margin
CAMERA_DIRECTION = (-0.7, 0.6, 0.7)
CAMERA_FOV_DEG = 50.0
CAMERA_MARGIN = 1.1
#: the camera and its target moved to the right by this fraction of the distance: the hand sits
#: left of the control panel (which covers the right of the page)
CAMERA_SHIFT = 0.12


# -- the export ------------------------------------------------------------------

def ensure_export(params_path, out, log: Callable[[str], None]):
    """(params, export folder, local URDF) of the hand in ``params_path`` (default
    params/phantom.toml); builds the export into ``out`` (default the build's default,
    exports/<hand>) first when it is missing or was built from other parameters or by other code
    (export.pipeline.ensure_export, not sliced: the viewer needs no print estimates)."""
    from ..calibration.effects import PARAMS_EFFECTS
    from ..export import pipeline
    from ..export.check import Export

    path = Path(params_path) if params_path is not None else DEFAULT_PARAMS
    export, params = pipeline.ensure_export(path, out, None, lambda msg: log(f"view: {msg}"), effects=PARAMS_EFFECTS,
                                            slice=False)
    return params, export, Export.open(export).local_urdf


def load_urdf(path: Path):
    """The URDF at ``path`` with its visual meshes and without its ``<mimic>`` elements: every
    joint is actuated and set by the viewer from the model."""
    from functools import partial

    import yourdfpy

    try:
        parsed = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False)
        for j in parsed.robot.joints:
            j.mimic = None
        urdf = yourdfpy.URDF(robot=parsed.robot, build_scene_graph=True, load_meshes=True,
                             filename_handler=partial(yourdfpy.filename_handler_magic, dir=str(path.parent)))
    except Exception as exc:  # yourdfpy raises what lxml/trimesh raise
        raise UserError(f"{path}: cannot load the robot description ({type(exc).__name__}: {exc}); "
                        "rebuild it with phantom-cad build") from exc
    missing = [j.name for j in JOINTS if j.name not in urdf.actuated_joint_names]
    if missing:
        raise UserError(f"{path}: the robot description has no revolute joint {', '.join(missing)}; "
                        "rebuild it with phantom-cad build")
    if urdf.scene is None or not urdf.scene.geometry:
        raise UserError(f"{path}: the robot description has no visual mesh; rebuild it with phantom-cad build")
    return urdf


# -- the viewer ------------------------------------------------------------------

def _shown_path(path: Path) -> str:
    """``path`` relative to the working directory when it is below it, else as it is."""
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


class Viewer:
    """A running viewer: ``server`` (viser), the GUI handles (``sliders`` in u order,
    ``compensated``, ``joints_md``, ``info``: hand, parameter file and digest, URDF), the
    scene's link frames (``frames``, link name -> viser frame, pose = the link's pose in the
    palm frame), and the state it shows: ``u``, ``q`` (radians), ``model`` ("analytic" or
    "compensated"). ``stop()`` ends it."""

    def __init__(self, server, hand, urdf, export: Path, urdf_path: Path):
        import numpy as np

        self.server, self.hand, self.urdf = server, hand, urdf
        self.export, self.urdf_path = export, urdf_path
        self.params = hand.params
        self._lock = threading.RLock()
        self.u = np.zeros(len(SERVOS))
        self.q = np.zeros(len(JOINTS))
        self.model = "analytic"
        self.updates = 0
        self._batch = False
        self.frames: dict[str, Any] = {}
        self._build_scene()
        self._build_gui()
        self.update()
        self._set_camera()

    # scene
    def _build_scene(self) -> None:
        import numpy as np

        scene, graph = self.urdf.scene, self.urdf.scene.graph
        # Light without shadows nor the image-based environment map: the meshes have some 300 000
        # triangles, and those make every frame many times dearer (software WebGL takes seconds a
        # frame with them, well under one without); a hemisphere light fills in instead.
        self.server.scene.configure_environment_map(hdri=None)
        self.server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        self.server.scene.add_light_hemisphere(f"{ROOT_NODE}_fill", sky_color=(255, 255, 255),
                                               ground_color=(110, 110, 120), intensity=1.0,
                                               position=(0.0, 0.0, 1.0))
        self.base = graph.base_frame
        for link in self.urdf.link_map:
            self.frames[link] = self.server.scene.add_frame(f"{ROOT_NODE}/{link}", show_axes=False)
        for node in graph.nodes_geometry:
            link = graph.transforms.parents[node]
            mesh = scene.geometry[graph[node][1]].copy()
            mesh.apply_transform(self.urdf.get_transform(node, link))
            try:
                color = tuple(int(c) for c in np.asarray(mesh.visual.main_color)[:3])
            except (AttributeError, ValueError):
                color = (160, 160, 160)
            self.server.scene.add_mesh_simple(f"{ROOT_NODE}/{link}/{node}", mesh.vertices, mesh.faces,
                                              color=color, material="standard", cast_shadow=False,
                                              receive_shadow=False)

    def _set_camera(self) -> None:
        """The whole hand in view, at rest and flexed: the camera looks at the centre of the
        rest pose's bounding box from the thumb side, in front of the fingertips and above
        the back of the hand, far enough for the sphere around that box (then both move
        sideways, see CAMERA_SHIFT)."""
        import numpy as np

        lo, hi = np.asarray(self.urdf.scene.bounds, dtype=float)
        center = (lo + hi) / 2
        radius = float(np.linalg.norm(hi - lo)) / 2
        fov = units.rad(CAMERA_FOV_DEG)
        direction = np.asarray(CAMERA_DIRECTION, dtype=float)
        if self.params.side == "left":   # mirrored hand: its thumb is at +x
            direction[0] = -direction[0]
        direction /= np.linalg.norm(direction)
        cam = self.server.initial_camera
        cam.up = (0.0, 0.0, 1.0)
        cam.fov = float(fov)
        cam.near = radius / 50
        cam.far = radius * 200
        distance = radius * CAMERA_MARGIN / np.sin(fov / 2)
        right = np.cross(-direction, (0.0, 0.0, 1.0))
        shift = right / np.linalg.norm(right) * distance * CAMERA_SHIFT
        cam.look_at = tuple(center + shift)
        cam.position = tuple(center + shift + direction * distance)

    # GUI
    def _build_gui(self) -> None:
        from html import escape

        from ..units import deg

        gui, p, hand = self.server.gui, self.params, self.hand
        # wide enough for the digest; no share button (it would ask viser's public relay server)
        gui.configure_theme(control_width="large", show_share_button=False)
        source = _shown_path(Path(p.source)) if p.source else "-"
        self.info = gui.add_html(
            "<div style='font-size: 0.85em; line-height: 1.5; padding: 0 0.75em'>"
            f"<b>{escape(p.name)}</b> ({escape(p.side)}), <code>{escape(source)}</code><br>params digest "
            f"<code style='word-break: break-all'>{p.digest}</code><br>robot description "
            f"<code style='word-break: break-all'>{escape(_shown_path(self.urdf_path))}</code></div>")
        sliders = []
        with gui.add_folder("servo commands u (rad)"):
            for sv in SERVOS:
                lo, hi = float(hand.u_min[sv.index]), float(hand.u_max[sv.index])
                s = gui.add_slider(f"{sv.label} {sv.name}", min=lo, max=hi, step=SLIDER_STEP,
                                   initial_value=min(max(0.0, lo), hi),
                                   hint=f"{sv.label} ({sv.name}) in radians; travel "
                                        f"[{deg(lo):.1f}, {deg(hi):.1f}] deg")
                s.on_update(lambda _event: self.update())
                sliders.append(s)
        self.sliders = tuple(sliders)
        self.compensated = gui.add_checkbox(
            "compensated", initial_value=False,
            hint="off: analytic model (eq. 2-10); on: the printed routing's statics (return-cord tension, "
                 "the loops' and the drive's stretch; the paper's eq. 11-14 for a calibrated file)")
        self.compensated.on_update(lambda _event: self.update())
        with gui.add_folder("joint angles (deg)"):
            self.joints_md = gui.add_markdown("")

    def _joints_table(self) -> str:
        from ..units import deg

        rows = [f"model: **{self.model}**", "", "| servo | | deg |", "|---|---|---:|"]
        rows += [f"| {sv.label} | {sv.name} | {deg(self.u[sv.index]):.{SHOWN_DECIMALS}f} |" for sv in SERVOS]
        rows += ["", "| joint | | deg |", "|---|---|---:|"]
        rows += [f"| {j.label} | {j.name} | {deg(self.q[j.index]):.{SHOWN_DECIMALS}f} |" for j in JOINTS]
        return "\n".join(rows)

    def update(self) -> None:
        """Read the sliders and the toggle, run the model, pose every link, refresh the table."""
        import numpy as np
        from viser import transforms as tf

        with self._lock:
            if self._batch:
                return
            u = np.array([float(s.value) for s in self.sliders])
            compensated = bool(self.compensated.value)
            q = np.asarray(self.hand.forward(u, compensated=compensated), dtype=float)
            self.urdf.update_cfg({j.name: float(q[j.index]) for j in JOINTS})
            poses = {link: self.urdf.get_transform(link, self.base) for link in self.frames}
            self.u, self.q = u, q
            self.model = "compensated" if compensated else "analytic"
            with self.server.atomic():
                for link, T in poses.items():
                    frame = self.frames[link]
                    frame.wxyz = tf.SO3.from_matrix(T[:3, :3]).wxyz
                    frame.position = T[:3, 3]
                self.joints_md.content = self._joints_table()
            self.updates += 1

    def set_u(self, u, compensated: Optional[bool] = None) -> None:
        """Set the sliders (and the toggle) from Python, as a user would; the viewer updates."""
        with self._lock:
            self._batch = True          # one update for all the handles, not one per handle
            try:
                if compensated is not None:
                    self.compensated.value = bool(compensated)
                for s, v in zip(self.sliders, u):
                    s.value = float(v)
            finally:
                self._batch = False
            self.update()

    @property
    def url(self) -> str:
        host = self.server.get_host()
        if host in ("", "0.0.0.0", "::"):
            host = "127.0.0.1"
        if ":" in host:
            host = f"[{host}]"
        return f"http://{host}:{self.server.get_port()}"

    def stop(self) -> None:
        """Stop the server (and its threads); viser's "Server stopped" line is not printed."""
        with contextlib.redirect_stdout(io.StringIO()):
            self.server.stop()


def _check_host(host: str) -> None:
    """Refuse an address this machine cannot listen on (viser would wait for it forever)."""
    import socket

    try:
        family, kind, proto, _, addr = socket.getaddrinfo(host, 0, type=socket.SOCK_STREAM)[0]
    except (OSError, UnicodeError) as exc:
        raise UserError(f"--host {host}: unknown address ({getattr(exc, 'strerror', None) or exc})") from exc
    with socket.socket(family, kind, proto) as probe:
        try:
            probe.bind(addr)
        except OSError as exc:
            raise UserError(f"--host {host}: cannot listen on it ({exc.strerror or exc})") from exc


def start_viewer(params_path=None, out=None, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT,
                 log: Optional[Callable[[str], None]] = None) -> Viewer:
    """Start the viewer of the hand in ``params_path`` (default params/phantom.toml) on the
    export ``out`` (default exports/<hand>; built first when missing or stale) and return it,
    serving on ``host``:``port`` (0: any free port; a busy port: viser takes the next free one)."""
    import viser

    from .. import make_hand

    log = log or (lambda msg: print(msg, file=sys.stderr))
    _check_host(host)
    params, export, urdf_path = ensure_export(params_path, out, log)
    hand = make_hand(params)
    urdf = load_urdf(urdf_path)
    try:
        with contextlib.redirect_stdout(io.StringIO()):   # viser's banner: the command prints the URL
            server = viser.ViserServer(host=host, port=port, label=f"phantom-cad view: {params.name}",
                                       verbose=False)
    except OSError as exc:
        raise UserError(f"cannot serve on {host}:{port}: {exc.strerror or exc}") from exc
    try:
        return Viewer(server, hand, urdf, export, urdf_path)
    except BaseException:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
        raise


# -- the command -------------------------------------------------------------------

def view(
    params: Optional[Path] = typer.Option(None, "--params", "-p", dir_okay=False,
                                          help="Parameter file (default: params/phantom.toml)."),
    out: Optional[Path] = typer.Option(None, "--out", "-o", file_okay=False,
                                       help="Export folder to show (default exports/<hand.name>); built "
                                            "first when missing or built from other parameters or by other code."),
    port: int = typer.Option(DEFAULT_PORT, "--port", min=0, max=65535,
                             help="Port to serve on (0: any free port; a busy one: the next free one)."),
    host: str = typer.Option(DEFAULT_HOST, "--host",
                             help="Address to serve on (0.0.0.0 serves every network interface)."),
) -> None:
    """The hand in the browser (viser): servo sliders u1..u6, analytic / compensated model, joint angles.

    Shows the meshes of the export's robot description, every joint set by the kinematic model.
    Runs until Ctrl-C. See docs/viewer.md.
    """
    import time

    from ..export.results import BuildError

    def log(msg: str) -> None:
        typer.echo(one_line(msg), err=True)

    try:
        viewer = start_viewer(params, out, host=host, port=port, log=log)
    except BuildError as exc:
        typer.echo(f"error: {one_line(exc)}", err=True)
        raise typer.Exit(1)
    if port and viewer.server.get_port() != port:
        log(f"view: port {port} is busy; serving on {viewer.server.get_port()}")
    log(f"view: {viewer.params.name}, params digest {viewer.params.digest[:12]}, {viewer.urdf_path}")
    typer.echo(f"phantom-cad view: open {viewer.url} (Ctrl-C stops)")
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        viewer.stop()
