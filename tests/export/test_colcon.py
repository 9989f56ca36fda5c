"""The description package built for real: ``colcon build`` (Debian's colcon and ament_cmake,
installed by .ci/sysdeps) builds and installs the exported package of the default and the left
hand, and every ``package://`` URI of the installed URDF resolves through the ament index
(``ament_index_python``, in a process with the install's ``setup.sh`` sourced) to a file of the
install, from which yourdfpy loads the hand.

Known answers: colcon, ament_cmake and ament_index_python themselves; the exported package's own
files (the install holds each, byte for byte).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

COLCON = shutil.which("colcon")


def _ament_python() -> str | None:
    """The Python colcon runs on (its script's interpreter), when it has ament_index_python: the
    Debian packages install ament_package and ament_index_python for it, not for the test's."""
    if COLCON is None:
        return None
    first = Path(COLCON).read_text(encoding="utf-8", errors="replace").split("\n", 1)[0]
    python = first[2:].strip().split()[0] if first.startswith("#!") else None
    if python is None or subprocess.run([python, "-c", "import ament_index_python, ament_package"],
                                        capture_output=True).returncode:
        return None
    return python


PYTHON = _ament_python()
pytestmark = pytest.mark.skipif(PYTHON is None, reason="colcon, ament_cmake or ament_index_python not installed "
                                "(Debian: colcon python3-colcon-ros ament-cmake python3-ament-index; .ci/sysdeps)")

#: run with the install's setup.sh sourced: every package:// URI of the URDF, resolved through the
#: ament index, as JSON {uri: path}
_RESOLVE = """
import json, sys, xml.etree.ElementTree as ET
from ament_index_python.packages import get_package_share_directory
uris = sorted({m.get("filename") for m in ET.parse(sys.argv[1]).getroot().iter("mesh")})
out = {}
for uri in uris:
    pkg, _, rel = uri.removeprefix("package://").partition("/")
    out[uri] = get_package_share_directory(pkg) + "/" + rel
print(json.dumps(out))
"""


@pytest.fixture(scope="module", params=["default", "left"])
def installed(request, hand_export, tmp_path_factory):
    """(source package folder, workspace, package name, hand name) of one hand's description package, built
    and installed by colcon in a workspace of its own."""
    from phantom_cad.export.description import package_name

    result = hand_export(request.param)
    source = result.out_dir / "description"
    ws = tmp_path_factory.mktemp(f"colcon_{request.param}")
    shutil.copytree(source, ws / "src" / source.name)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("AMENT_", "COLCON_", "CMAKE_PREFIX"))}
    env["COLCON_HOME"] = str(ws / ".colcon")     # no user defaults
    # ament_cmake runs its templates on the CMake-found Python3: the one with ament_package, not
    # whichever python3 is first on PATH (a venv's, pyenv's)
    run = subprocess.run([COLCON, "--log-base", "log", "build", "--event-handlers", "console_direct-",
                          "--cmake-args", f"-DPython3_EXECUTABLE={PYTHON}"],
                         cwd=ws, env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    return source, ws, package_name(result.hand), result.hand


def test_colcon_installs_every_file_of_the_package(installed):
    source, ws, pkg, hand = installed
    share = ws / "install" / pkg / "share" / pkg
    files = sorted(p.relative_to(source) for p in source.rglob("*") if p.is_file())
    assert Path(f"urdf/{hand}.urdf") in files and Path("package.xml") in files
    for rel in files:
        if rel.name == "CMakeLists.txt":     # the build's, not installed
            continue
        assert (share / rel).read_bytes() == (source / rel).read_bytes(), rel
    marker = ws / "install" / pkg / "share" / "ament_index" / "resource_index" / "packages" / pkg
    assert marker.is_file()      # ament_package() registered it in the index


def test_package_uris_resolve_through_the_ament_index(installed):
    source, ws, pkg, hand = installed
    install = ws / "install"
    urdf = install / pkg / "share" / pkg / "urdf" / f"{hand}.urdf"
    env = {k: v for k, v in os.environ.items() if not k.startswith(("AMENT_", "COLCON_"))}
    run = subprocess.run(["sh", "-c", '. "$1" && exec "$2" -c "$3" "$4"', "sh", str(install / "setup.sh"),
                          PYTHON, _RESOLVE, str(urdf)], env=env, capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    resolved = json.loads(run.stdout)
    meshes = [m.get("filename") for m in ET.parse(urdf).getroot().iter("mesh")]
    assert meshes and set(resolved) == set(meshes)
    assert all(uri.startswith(f"package://{pkg}/meshes/") for uri in resolved)
    for uri, path in resolved.items():
        path = Path(path)
        assert path.is_file() and path.resolve().is_relative_to(install.resolve()), uri
        # the installed mesh is the exported one
        assert path.read_bytes() == (source / uri.removeprefix(f"package://{pkg}/")).read_bytes()

    # yourdfpy loads the hand from the installed tree, each mesh found through the index
    yourdfpy = pytest.importorskip("yourdfpy")
    loaded = []
    robot = yourdfpy.URDF.load(str(urdf), load_meshes=True, build_collision_scene_graph=True,
                               load_collision_meshes=True,
                               filename_handler=lambda fname: loaded.append(fname) or resolved[fname])
    reference = yourdfpy.URDF.load(str(source / "urdf" / f"{hand}.local.urdf"), load_meshes=False)
    assert set(robot.link_map) == set(reference.link_map) and set(loaded) == set(meshes)
    for scene in (robot.scene, robot.collision_scene):
        assert 0.1 < max(scene.extents) < 1.0      # a hand with its forearm, metres
