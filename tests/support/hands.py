"""The three reference hands the slow tests build, and where a test finds their solids.

* :data:`HANDS`: the default hand, its left twin, and a hand of hand_length 170 mm (a file of its
  own, params/examples/small.toml: the fingers narrower, the pitch shorter, its CMC placement
  solved for it).
* :func:`hand_source`: the parameter file and side ``phantom-cad build`` is given for one of them,
  or for ``"slender"`` (params/examples/slender.toml), a fourth hand some tests export.
* :func:`hand_document`: its plain parameter document.
* :func:`export_entries`, :func:`entry_solids`, :func:`entry_meshes`: the solids and meshes of a
  built export, read back from the part cache entries its manifest names (the BREP each part was
  exported from, and the mesh its STL, its robot description and its pictures were made of).
"""

from __future__ import annotations

import copy
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SMALL = ROOT / "params" / "examples" / "small.toml"
SLENDER = ROOT / "params" / "examples" / "slender.toml"

#: name -> (parameter file or None: the default file, side given on the command line or None)
_SOURCES = {"default": (None, None), "left": (None, "left"), "hand_length_170": (SMALL, None),
            "slender": (SLENDER, None), "default_unsliced": (None, None)}
#: the reference hands
HANDS = ("default", "left", "hand_length_170")
#: the hands exported sliced (when PrusaSlicer is installed) as a user would, the description's
#: masses then the slicer's: the default hand (the tests read its estimates) and the 170 mm hand
#: (its cylinder hold, tests/export/test_mjcf.py, on the slicer's masses as a user's export has
#: them); the left hand's parts meet PrusaSlicer through their projects
#: (tests/export/test_project3mf.py). ``"default_unsliced"`` is the default hand exported without
#: the slicer (its parts from the run's cache): masses that do not vary from run to run, for the
#: grasp table (tests/export/test_grasps.py)
SLICED = ("default", "hand_length_170")


def hand_source(kind: str) -> tuple[Path | None, str | None]:
    """(parameter file or None: the default file, side or None) of one of :data:`HANDS` or of
    ``"slender"``, as ``build_hand`` takes them."""
    return _SOURCES[kind]


def hand_document(kind: str) -> dict:
    """The plain document of one of :data:`HANDS` or of ``"slender"``."""
    from phantom_cad.canon import plain
    from phantom_cad.params.io import load_params

    path, side = hand_source(kind)
    doc = copy.deepcopy(plain(load_params(path).document))
    if side is not None:
        doc["hand"]["side"] = side
    return doc


def export_entries(result, cache_root: Path) -> dict[str, Path]:
    """name -> part cache entry of every part of a BuildResult, each checked against the hashes it
    was sealed with (the cache's own check)."""
    from phantom_cad.export.cache import Cache

    cache = Cache(cache_root)
    out = {}
    for e in result.manifest["parts"]:
        problem = cache.part_problem(e["cache_key"])
        assert problem is None, f"{e['name']}: the part cache entry of the export is {problem}"
        out[e["name"]] = cache.part_dir(e["cache_key"])
    return out


def entry_solids(entries: dict[str, Path]) -> dict:
    """{name: solid in its link frame, mm} of :func:`export_entries` (each part's part.brep)."""
    from phantom_cad.export import step_stl

    return {n: step_stl.read_brep(d / "part.brep") for n, d in entries.items()}


def entry_meshes(entries: dict[str, Path]) -> dict:
    """{name: (vertices, faces)} in the link frame, mm, at the export's STL tolerance, of
    :func:`export_entries` (each part's mesh.npz)."""
    import numpy as np

    out = {}
    for n, d in entries.items():
        with np.load(d / "mesh.npz") as m:
            out[n] = (m["vertices"], m["faces"].astype(np.int64))
    return out


#: the placement ``phantom-cad size --hand-length 170.4 --hand-breadth 76.8`` searched when its rule
#: was the capsules' opposition margin alone (offset mm, axis deg): there the thumb's tip end, not its
#: pad, meets the index pad, on the solids and on the printed tips (tests/test_printed_tips.py,
#: tests/cad/test_printed_tips_on_solids.py)
RIM_PLACEMENT = ([-22.687, -64.409, -30.4604], [-22.6133, 20.9841, -52.114])


def rim_hand():
    """The 170.4 x 76.8 mm hand ``size`` writes (the reference placement scaled) moved to
    :data:`RIM_PLACEMENT`: a Hand."""
    from phantom_cad import make_hand
    from phantom_cad.params import parse
    from phantom_cad.sizing import Person, size

    doc = copy.deepcopy(size(Person(170.4, 76.8, "right", "rim"), search=False).document)
    doc["palm"]["thumb_cmc_offset_mm"], doc["palm"]["thumb_cmc_axis_deg"] = RIM_PLACEMENT
    return make_hand(parse(doc))


#: the CMC placement the search found for the population's 213 x 75 mm hand (L213-w50-B75 of
#: bench/population.py): heel length (mm), CMC offset (mm), CMC axis (deg)
UNDER_RING_PLACEMENT = (49.4, [-45.8287, -81.6744, -28.9025], [-16.6641, 20.484, -53.679])


def under_ring_hand():
    """The 213 x 75 mm hand ``size`` writes at :data:`UNDER_RING_PLACEMENT`, where the thumb's tip
    reaches under the ring's middle phalanx at the first ring contact: a Hand."""
    from phantom_cad import make_hand
    from phantom_cad.params import parse
    from phantom_cad.sizing import Person, build_document

    doc = build_document(Person(213.0, 75.0))
    heel, offset, axis = UNDER_RING_PLACEMENT
    doc["palm"].update(heel_length_mm=heel, thumb_cmc_offset_mm=offset, thumb_cmc_axis_deg=axis)
    return make_hand(parse(doc))
