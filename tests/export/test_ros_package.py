"""The ROS 2 side of the description package: what can be checked without ROS 2.

package.xml is read and validated by catkin_pkg (the parser colcon and rosdep use), the launch
file is compiled and run against stand-ins of the ROS launch API (which record what it starts),
the RViz config is read as YAML, and CMakeLists.txt installs every folder the package has.
Known answers: the URDF's root link read here from the file, the file system.
"""

from __future__ import annotations

import re
import sys
import types
import xml.etree.ElementTree as ET

import pytest

yaml = pytest.importorskip("yaml")


def test_package_xml_is_valid_format_3(pkg):
    catkin_pkg = pytest.importorskip("catkin_pkg.package")
    package = catkin_pkg.parse_package(str(pkg / "package.xml"))     # validates: raises on a bad manifest
    assert package.package_format == 3 and package.name == "phantom_description"
    assert package.get_build_type() == "ament_cmake"
    deps = {d.name for d in package.exec_depends}
    assert {"robot_state_publisher", "joint_state_publisher_gui", "rviz2", "xacro", "launch_ros"} <= deps
    assert package.licenses == ["MIT"] and "MIT License" in (pkg / "LICENSE").read_text()
    assert package.version in (pkg / "CHANGELOG.md").read_text()


def test_cmake_installs_every_folder_and_file(pkg):
    text = (pkg / "CMakeLists.txt").read_text()
    assert re.search(r"project\(phantom_description\)", text)
    dirs = set(re.search(r"install\(DIRECTORY ([^)]*?) DESTINATION", text).group(1).split())
    files = set(re.search(r"install\(FILES ([^)]*?) DESTINATION", text).group(1).split())
    on_disk = {p.name for p in pkg.iterdir() if p.is_dir()}
    assert dirs == on_disk == {"config", "launch", "meshes", "mjcf", "rviz", "urdf"}
    assert all((pkg / f).is_file() for f in files) and {"LICENSE", "CHANGELOG.md"} <= files


class _Recorder:
    """A stand-in for a ROS launch class: records its arguments."""

    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs


def _stub_ros(monkeypatch, share):
    """Stand-ins of ament_index_python, launch and launch_ros in sys.modules."""
    mods = {}
    for name in ("ament_index_python", "ament_index_python.packages", "launch", "launch.actions",
                 "launch.conditions", "launch.substitutions", "launch_ros", "launch_ros.actions"):
        mods[name] = types.ModuleType(name)
        monkeypatch.setitem(sys.modules, name, mods[name])
    looked_up = []
    mods["ament_index_python.packages"].get_package_share_directory = \
        lambda p: looked_up.append(p) or str(share)
    for mod, names in (("launch", ["LaunchDescription"]), ("launch.actions", ["DeclareLaunchArgument"]),
                       ("launch.conditions", ["IfCondition", "UnlessCondition"]),
                       ("launch.substitutions", ["LaunchConfiguration"]), ("launch_ros.actions", ["Node"])):
        for n in names:
            setattr(mods[mod], n, type(n, (_Recorder,), {}))
    return looked_up


def test_launch_file_compiles_and_starts_the_display(pkg, monkeypatch):
    path = pkg / "launch" / "display.launch.py"
    code = compile(path.read_text(), str(path), "exec")
    looked_up = _stub_ros(monkeypatch, pkg)
    namespace: dict = {"__name__": "display_launch"}
    exec(code, namespace)
    ld = namespace["generate_launch_description"]()
    assert looked_up == ["phantom_description"]
    actions = ld.args[0]
    nodes = {a.kwargs["package"]: a.kwargs for a in actions if type(a).__name__ == "Node"}
    assert set(nodes) == {"robot_state_publisher", "joint_state_publisher", "joint_state_publisher_gui", "rviz2"}
    described = nodes["robot_state_publisher"]["parameters"][0]["robot_description"]
    assert described == (pkg / "urdf" / "phantom.urdf").read_text()     # the package:// URDF
    rviz = nodes["rviz2"]["arguments"]
    assert rviz[0] == "-d" and (pkg / "rviz" / "display.rviz").samefile(rviz[1])
    assert [a.args[0] for a in actions if type(a).__name__ == "DeclareLaunchArgument"] == ["gui"]


def test_rviz_config_shows_the_robot_from_its_root(pkg):
    config = yaml.safe_load((pkg / "rviz" / "display.rviz").read_text())
    manager = config["Visualization Manager"]
    root = ET.parse(pkg / "urdf" / "phantom.urdf").getroot()
    children = {j.find("child").get("link") for j in root.iter("joint")}
    roots = [ln.get("name") for ln in root.iter("link") if ln.get("name") not in children]
    assert roots == [manager["Global Options"]["Fixed Frame"]]
    robot = next(d for d in manager["Displays"] if d["Class"] == "rviz_default_plugins/RobotModel")
    assert robot["Enabled"] and robot["Description Topic"]["Value"] == "/robot_description"
    assert robot["Description Topic"]["Durability Policy"] == "Transient Local"   # robot_state_publisher latches
    assert manager["Views"]["Current"]["Class"] == "rviz_default_plugins/Orbit"
