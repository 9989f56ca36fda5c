"""The exporters: one class per output of a build, run in order by the pipeline.

Known answers: the RViz config's YAML written out by hand here, in the layout RViz 2 writes.
"""

from __future__ import annotations

import inspect

import pytest

from phantom_cad.export import exporters
from phantom_cad.export.exporters import EXPORTERS, Exporter


def test_every_output_is_one_exporter_in_the_list():
    assert inspect.isabstract(Exporter)
    classes = [type(e) for e in EXPORTERS]
    assert len(set(classes)) == len(classes)
    names = [e.name for e in EXPORTERS]
    assert all(names) and len(set(names)) == len(names)
    # every concrete exporter of the module is in the list
    defined = {c for _, c in inspect.getmembers(exporters, inspect.isclass)
               if issubclass(c, Exporter) and not inspect.isabstract(c) and c.__module__ == exporters.__name__}
    assert defined == set(classes)


def test_the_order_keeps_the_assembly_workers_busy_and_the_manifest_last():
    """The assembly STEP and its picture are finished in the workers while the description, the
    BOM and the routing are written: those come before the first exporter that waits for them; the
    manifest lists every file, so it is last."""
    order = [type(e) for e in EXPORTERS]
    first_wait = min(order.index(exporters.AssemblyStep), order.index(exporters.AssemblyRender))
    for early in (exporters.DescriptionMeshes, exporters.Urdf, exporters.Mjcf, exporters.RosPackage,
                  exporters.Bom, exporters.Routing):
        assert order.index(early) < first_wait
    assert order.index(exporters.DescriptionMeshes) < order.index(exporters.Mjcf)   # MuJoCo reads the meshes
    assert order[-1] is exporters.Manifest


def test_the_rviz_yaml_is_written_as_rviz_writes_it():
    pytest.importorskip("yaml")
    from phantom_cad.export.description import _yaml

    config = {"Panels": [{"Class": "rviz_common/Displays", "Name": "Displays"}],
              "Manager": {"Class": "", "Displays": [{"Cell Size": 0.01, "Enabled": True, "Count": 40,
                                                     "Frame": "<Fixed Frame>"}],
                          "Global Options": {"Fixed Frame": "palm", "Background Color": "48; 48; 48"},
                          "Empty": []}}
    assert _yaml(config) == (
        "Panels:\n"
        "  - Class: rviz_common/Displays\n"
        "    Name: Displays\n"
        "Manager:\n"
        "  Class: ''\n"
        "  Displays:\n"
        "    - Cell Size: 0.01\n"
        "      Enabled: true\n"
        "      Count: 40\n"
        "      Frame: '<Fixed Frame>'\n"
        "  Global Options:\n"
        "    Fixed Frame: palm\n"
        "    Background Color: '48; 48; 48'\n"
        "  Empty: []\n")


def test_every_print_aid_has_its_exporter():
    from phantom_cad.cad.print_aids import AIDS

    assert [e.aid for e in EXPORTERS if isinstance(e, exporters.PrintAidFiles)] == list(AIDS)
