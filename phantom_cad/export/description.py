"""The robot description package of a build: ``exports/<hand>/description/``.

A ROS 2 package named ``<hand>_description`` that is also usable without ROS::

    package.xml  CMakeLists.txt  README.md  LICENSE  CHANGELOG.md
    config/retargeting/<hand>_<side>_{vector,position}.yml   dex-retargeting configs (export/retargeting.py)
    launch/display.launch.py    robot_state_publisher + joint_state_publisher(_gui) + RViz
    rviz/display.rviz           RViz 2 config: fixed frame the root link, RobotModel, TF
    mjcf/<hand>.xml  mjcf/scene.xml  MuJoCo (built with MjSpec, export/mjcf.py); scene: floor, light
    urdf/<hand>.urdf            package:// mesh URIs (ROS, RViz)
    urdf/<hand>.local.urdf      the same with paths relative to the file (yourdfpy, PyBullet, MuJoCo, Pinocchio)
    meshes/visual/<link>.stl    metres, in the link frame (the solid's tessellation, not the print pose)
    meshes/collision/<link>.stl its convex hull (<link>_<k>.stl: the convex solids it is fused from)

The model comes from :mod:`phantom_cad.export.robot`; docs/descriptions.md gives the conventions.
"""

from __future__ import annotations

import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from .. import units
from . import step_stl
from .mjcf import mjcf_bytes, scene_bytes
from .robot import RobotModel, collision_stems
from .urdf import urdf_bytes

#: the package's version, bumped when its layout changes
PACKAGE_VERSION = "0.2.0"


def package_name(hand: str) -> str:
    """A ROS package name (``^[a-z][a-z0-9_]*$``) from the hand's name: ``<hand>_description``."""
    base = re.sub(r"[^a-z0-9_]+", "_", hand.lower()).strip("_") or "hand"
    if not base[0].isalpha():
        base = f"hand_{base}"
    return f"{base}_description"


#: the description's meshes of a part, as its part-cache entry holds them: the visual STL and
#: the convex collision pieces (``c<k>_vertices`` / ``c<k>_faces``, metres)
MESH_FILES = {"visual": "visual.stl", "collision": "collision.npz"}
#: how far a vertex of the exact hull may lie outside the light collision hull (metres): qhull's
#: ``W`` option drops the hull vertices within it of a facet, which takes a finger's hull from
#: about 1,000 faces to at most about 150 (docs/descriptions.md)
HULL_TOLERANCE = 0.1 * units.MM


def collision_hull(vertices: np.ndarray, tolerance: float = HULL_TOLERANCE) -> tuple[np.ndarray, np.ndarray]:
    """A light convex collision shape of a mesh: the convex hull (qhull) of those of its vertices
    that lie farther than ``tolerance`` outside the hull of the others, so its vertices are
    vertices of the mesh and no vertex of the mesh lies more than ``tolerance`` outside it."""
    import trimesh
    from scipy.spatial import ConvexHull

    points = np.asarray(vertices, float)
    kept = np.sort(ConvexHull(points, qhull_options=f"W{tolerance:.12g} Qt").vertices)
    while True:  # qhull's W is approximate: add back the vertices still farther out than tolerance
        planes = ConvexHull(points[kept]).equations
        out = np.flatnonzero((points @ planes[:, :3].T + planes[:, 3]).max(axis=1) > tolerance)
        if not len(out):
            break
        kept = np.union1d(kept, out)
    hull = trimesh.convex.convex_hull(points[kept])  # the same polytope, faces oriented outwards
    return np.asarray(hull.vertices, float), np.asarray(hull.faces, np.int64)


def part_meshes(vertices_mm: np.ndarray, faces: np.ndarray, name: str,
                pieces_mm: list[np.ndarray] = ()) -> dict[str, bytes]:
    """The description's meshes of one part (metres, link frame), by MESH_FILES kind: made once
    per part by the build worker and kept in its cache entry. The collision shape is one light
    convex hull (collision_hull) of the part, or, for a part that names the convex solids it is
    fused from (``Part.collision_solids``: the palm, the forearm module), one of each solid's
    tessellation (``pieces_mm``, vertices in mm), in a fixed order."""
    import io

    v = np.asarray(vertices_mm, float) * units.MM
    if len(pieces_mm):
        pieces = sorted((collision_hull(np.asarray(p, float) * units.MM) for p in pieces_mm),
                        key=lambda p: tuple(np.round(p[0].mean(axis=0), 9)))
    else:
        pieces = [collision_hull(v)]
    arrays = {}
    for k, (pv, pf) in enumerate(pieces):
        arrays[f"c{k}_vertices"], arrays[f"c{k}_faces"] = pv, pf.astype(np.int32)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return {"visual": step_stl.stl_bytes(v, faces, name, "m"), "collision": buf.getvalue()}


def collision_pieces(data: bytes) -> list[tuple[np.ndarray, np.ndarray]]:
    """The convex pieces of a cached ``collision.npz``, in order."""
    import io

    with np.load(io.BytesIO(data)) as z:
        n = len(z.files) // 2
        return [(z[f"c{k}_vertices"], z[f"c{k}_faces"]) for k in range(n)]


def _package_xml(pkg: str, hand: str) -> bytes:
    root = ET.Element("package", {"format": "3"})
    for tag, text in (("name", pkg), ("version", PACKAGE_VERSION),
                      ("description", f"Robot description of the {hand} hand (URDF, meshes), generated by phantom_cad"),
                      ("maintainer", "phantom_cad"), ("license", "MIT")):
        e = ET.SubElement(root, tag, {"email": "phantom_cad@example.org"} if tag == "maintainer" else {})
        e.text = text
    ET.SubElement(root, "buildtool_depend").text = "ament_cmake"
    for dep in EXEC_DEPENDS:
        ET.SubElement(root, "exec_depend").text = dep
    export = ET.SubElement(root, "export")
    ET.SubElement(export, "build_type").text = "ament_cmake"
    ET.indent(root, space="  ")
    return (b'<?xml version="1.0"?>\n'
            b'<?xml-model href="http://download.ros.org/schema/package_format3.xsd" '
            b'schematypens="http://www.w3.org/2001/XMLSchema"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n")


#: what display.launch.py starts or imports (package.xml's exec_depend)
EXEC_DEPENDS = ("ament_index_python", "launch", "launch_ros", "robot_state_publisher", "joint_state_publisher",
                "joint_state_publisher_gui", "rviz2", "xacro")
#: the folders the package installs into share/<package>
INSTALL_DIRS = ("config", "launch", "meshes", "mjcf", "rviz", "urdf")


def _cmakelists(pkg: str) -> str:
    return (f"cmake_minimum_required(VERSION 3.8)\nproject({pkg})\n\nfind_package(ament_cmake REQUIRED)\n\n"
            f"install(DIRECTORY {' '.join(INSTALL_DIRS)} DESTINATION share/${{PROJECT_NAME}})\n"
            "install(FILES LICENSE CHANGELOG.md README.md DESTINATION share/${PROJECT_NAME})\n\n"
            "ament_package()\n")


def _launch(pkg: str, hand: str) -> str:
    return f'''"""Display the {hand} hand in RViz 2: robot_state_publisher with urdf/{hand}.urdf,
joint_state_publisher_gui (sliders; gui:=false for joint_state_publisher) and RViz with
rviz/display.rviz.

    ros2 launch {pkg} display.launch.py

Generated by phantom_cad; do not edit.
"""

from pathlib import Path

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition, UnlessCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

PACKAGE = "{pkg}"
URDF = "urdf/{hand}.urdf"
RVIZ = "rviz/display.rviz"


def generate_launch_description():
    share = Path(get_package_share_directory(PACKAGE))
    robot_description = (share / URDF).read_text(encoding="utf-8")
    gui = LaunchConfiguration("gui")
    return LaunchDescription([
        DeclareLaunchArgument("gui", default_value="true",
                              description="Sliders (joint_state_publisher_gui) or none (joint_state_publisher)"),
        Node(package="robot_state_publisher", executable="robot_state_publisher", output="screen",
             parameters=[{{"robot_description": robot_description}}]),
        Node(package="joint_state_publisher_gui", executable="joint_state_publisher_gui", condition=IfCondition(gui)),
        Node(package="joint_state_publisher", executable="joint_state_publisher", condition=UnlessCondition(gui)),
        Node(package="rviz2", executable="rviz2", output="screen", arguments=["-d", str(share / RVIZ)]),
    ])
'''


#: a string RViz's own files leave unquoted; any other is written in single quotes
_PLAIN = re.compile(r"[A-Za-z_/][A-Za-z0-9_/ .-]*")


def _yaml(obj) -> str:
    """YAML of nested dicts, lists and scalars, block style, as RViz 2 writes its configs: lists
    indented under their key, and a string quoted unless it is a plain word or path (PyYAML leaves
    ``<Fixed Frame>`` bare)."""
    import yaml

    class Dumper(yaml.SafeDumper):
        def increase_indent(self, flow=False, indentless=False):
            return super().increase_indent(flow, False)

    def string(dumper, value):
        return dumper.represent_scalar("tag:yaml.org,2002:str", value, style=None if _PLAIN.fullmatch(value) else "'")

    Dumper.add_representer(str, string)
    return yaml.dump(obj, Dumper=Dumper, sort_keys=False, default_flow_style=False, width=1 << 16)


def _rviz(model: RobotModel) -> str:
    """RViz 2's display config: the root link as fixed frame, the robot model from
    /robot_description, TF, a grid, an orbit view framing a hand."""
    children = {j.child for j in model.joints}
    root = next(ln.name for ln in model.links if ln.name not in children)
    config = {"Panels": [{"Class": "rviz_common/Displays", "Name": "Displays"}],
              "Visualization Manager": {
                  "Class": "", "Displays": [
                      {"Class": "rviz_default_plugins/Grid", "Name": "Grid", "Enabled": True,
                       "Cell Size": 0.01, "Plane Cell Count": 40, "Reference Frame": "<Fixed Frame>"},
                      {"Class": "rviz_default_plugins/RobotModel", "Name": "RobotModel", "Enabled": True,
                       "Description Source": "Topic",
                       "Description Topic": {"Value": "/robot_description", "Depth": 5,
                                             "Durability Policy": "Transient Local",
                                             "History Policy": "Keep Last", "Reliability Policy": "Reliable"},
                       "Visual Enabled": True, "Collision Enabled": False, "Alpha": 1.0},
                      {"Class": "rviz_default_plugins/TF", "Name": "TF", "Enabled": False, "Marker Scale": 0.05}],
                  "Enabled": True,
                  "Global Options": {"Fixed Frame": root, "Background Color": "48; 48; 48", "Frame Rate": 30},
                  "Tools": [{"Class": "rviz_default_plugins/Interact"}, {"Class": "rviz_default_plugins/MoveCamera"}],
                  "Views": {"Current": {"Class": "rviz_default_plugins/Orbit", "Name": "Current View",
                                        "Distance": 0.45, "Focal Point": {"X": 0.0, "Y": 0.0, "Z": 0.08},
                                        "Pitch": 0.5, "Yaw": 0.8, "Target Frame": "<Fixed Frame>"}}}}
    return "# RViz 2 config of the " + model.name + " hand, generated by phantom_cad\n" + _yaml(config)


_LICENSE = """MIT License

Copyright (c) the phantom_cad contributors

Permission is hereby granted, free of charge, to any person obtaining a copy
of this software and associated documentation files (the "Software"), to deal
in the Software without restriction, including without limitation the rights
to use, copy, modify, merge, publish, distribute, sublicense, and/or sell
copies of the Software, and to permit persons to whom the Software is
furnished to do so, subject to the following conditions:

The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.

THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
"""


def _changelog(pkg: str, digest: str) -> str:
    return (f"# Changelog of {pkg}\n\n## {PACKAGE_VERSION}\n\n"
            f"- Generated by phantom_cad from the parameter file with digest `{digest}`.\n"
            "- URDF (package:// and relative mesh paths), MJCF and its scene, visual and collision meshes,\n"
            "  `launch/display.launch.py` and `rviz/display.rviz`.\n"
            "- `config/retargeting/`: dex-retargeting configs (vector, position) of the hand's side (0.2.0).\n")


def _readme(pkg: str, model: RobotModel) -> str:
    n_rev = sum(j.type == "revolute" for j in model.joints)
    n_mimic = sum(j.mimic is not None for j in model.joints)
    return (f"# {pkg}\n\nThe {model.name} hand ({model.side}), generated by phantom_cad from its parameter file.\n\n"
            f"- `urdf/{model.name}.urdf`: `package://{pkg}/...` mesh URIs, for ROS 2 (build this package with colcon).\n"
            f"- `urdf/{model.name}.local.urdf`: mesh paths relative to the file, for yourdfpy, PyBullet, MuJoCo, "
            "Pinocchio.\n"
            f"- {len(model.links)} links, {n_rev} revolute joints ({n_mimic} follow their chain's reference joint "
            "through `<mimic>`), fingertip frames `<digit>_tip`.\n"
            f"- `config/retargeting/`: dex-retargeting configs ({model.side} hand; vector and position retargeting of "
            "MediaPipe's 21 hand keypoints; their `frame` table says how keypoints enter the root frame).\n\n"
            "Units SI; meshes in metres in each link's frame. See phantom_cad's docs/descriptions.md.\n")


def _mjcf(model: RobotModel, folder: Path, part_dirs: dict[str, Path], cache) -> bytes:
    """The MJCF of the package (compiled by MuJoCo), from ``cache`` when it holds it: the key is
    the model, the bytes of every mesh it reads, the code and the versions (MuJoCo's among them),
    so a served MJCF is one MuJoCo compiled from the same inputs."""
    import hashlib

    from ..canon import canonical, sha256
    from .cache import cad_versions, code_digest

    if cache is None:
        return mjcf_bytes(model, folder)
    meshes = {}
    for stem in sorted({ln.mesh for ln in model.links if ln.mesh is not None}):
        meshes[stem] = [hashlib.sha256((part_dirs[stem] / MESH_FILES[k]).read_bytes()).hexdigest()
                        for k in sorted(MESH_FILES)]
    key = sha256(canonical({"model": model, "meshes": meshes, "code": code_digest(),
                            "versions": cad_versions()}))
    xml, _why = cache.read_mjcf(key)
    if xml is None:
        data = mjcf_bytes(model, folder)
        cache.write_mjcf(key, data.decode("utf-8"))
        return data
    return xml.encode("utf-8")


#: the package's own files (the ROS 2 package around the robot model), relative to its folder
PACKAGE_FILES = ("package.xml", "CMakeLists.txt", "README.md", "LICENSE", "CHANGELOG.md", "launch/display.launch.py",
                 "rviz/display.rviz")


def mesh_files(model: RobotModel) -> list[str]:
    """The meshes :func:`write_meshes` writes, relative to the package folder."""
    return [rel for ln in model.links if ln.mesh is not None
            for rel in [f"meshes/visual/{ln.mesh}.stl", *(f"meshes/collision/{stem}.stl" for stem in ln.collision)]]


def write_meshes(folder: Path, model: RobotModel, part_dirs: dict[str, Path]) -> None:
    """The visual and collision meshes of every link into ``folder`` (the package's). ``part_dirs``:
    mesh stem -> the part's cache entry (its MESH_FILES, from :func:`part_meshes`)."""
    for kind in MESH_FILES:
        (folder / "meshes" / kind).mkdir(parents=True)
    for ln in model.links:
        if ln.mesh is None:
            continue
        shutil.copyfile(part_dirs[ln.mesh] / MESH_FILES["visual"], folder / "meshes" / "visual" / f"{ln.mesh}.stl")
        pieces = collision_pieces((part_dirs[ln.mesh] / MESH_FILES["collision"]).read_bytes())
        if collision_stems(ln.mesh, len(pieces)) != ln.collision:
            raise ValueError(f"{ln.name}: {len(pieces)} collision pieces in the cache, the model has "
                             f"{len(ln.collision)}")
        for stem, (v, f) in zip(ln.collision, pieces):
            (folder / "meshes" / "collision" / f"{stem}.stl").write_bytes(step_stl.stl_bytes(v, f, stem, "m"))


def urdf_files(model: RobotModel) -> list[str]:
    return [f"urdf/{model.name}.urdf", f"urdf/{model.name}.local.urdf"]


def write_urdf(folder: Path, model: RobotModel) -> None:
    """The URDF twice: with ``package://`` mesh URIs (ROS) and with paths relative to the file."""
    pkg = package_name(model.name)
    note = f"generated by phantom_cad: {model.name} hand ({model.side}); do not edit"
    (folder / "urdf").mkdir(parents=True)
    (folder / "urdf" / f"{model.name}.urdf").write_bytes(
        urdf_bytes(model, lambda kind, stem: f"package://{pkg}/meshes/{kind}/{stem}.stl", note))
    (folder / "urdf" / f"{model.name}.local.urdf").write_bytes(
        urdf_bytes(model, lambda kind, stem: f"../meshes/{kind}/{stem}.stl", note))


def mjcf_files(model: RobotModel) -> list[str]:
    return [f"mjcf/{model.name}.xml", "mjcf/scene.xml"]


def write_mjcf(folder: Path, model: RobotModel, part_dirs: dict[str, Path], cache=None) -> None:
    """The MJCF and its scene (floor, light); MuJoCo compiles the model from the meshes
    :func:`write_meshes` wrote. ``cache``: the build's :class:`~phantom_cad.export.cache.Cache`,
    which keeps the compiled MJCF."""
    (folder / "mjcf").mkdir(parents=True)
    (folder / "mjcf" / f"{model.name}.xml").write_bytes(_mjcf(model, folder / "mjcf", part_dirs, cache))
    (folder / "mjcf" / "scene.xml").write_bytes(scene_bytes(f"{model.name}.xml", model.name))


def write_package(folder: Path, model: RobotModel, digest: str = "") -> None:
    """The package's own files (:data:`PACKAGE_FILES`); ``digest``: the parameter file's, recorded
    in CHANGELOG.md."""
    pkg = package_name(model.name)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "package.xml").write_bytes(_package_xml(pkg, model.name))
    (folder / "CMakeLists.txt").write_text(_cmakelists(pkg), encoding="utf-8")
    (folder / "README.md").write_text(_readme(pkg, model), encoding="utf-8")
    (folder / "LICENSE").write_text(_LICENSE, encoding="utf-8")
    (folder / "CHANGELOG.md").write_text(_changelog(pkg, digest), encoding="utf-8")
    (folder / "launch").mkdir()
    (folder / "launch" / "display.launch.py").write_text(_launch(pkg, model.name), encoding="utf-8")
    (folder / "rviz").mkdir()
    (folder / "rviz" / "display.rviz").write_text(_rviz(model), encoding="utf-8")


def summary(model: RobotModel, prefix: str) -> dict:
    """The manifest's record of the package written in the export's folder ``prefix``."""
    return {"package": package_name(model.name), "urdf": f"{prefix}/urdf/{model.name}.urdf",
            "local_urdf": f"{prefix}/urdf/{model.name}.local.urdf",
            "mjcf": f"{prefix}/mjcf/{model.name}.xml", "scene": f"{prefix}/mjcf/scene.xml",
            "masses_kg": {ln.name: round(ln.inertial.mass, 9) for ln in model.links if ln.inertial},
            "mass_source": sorted({ln.inertial.source for ln in model.links if ln.inertial})}
