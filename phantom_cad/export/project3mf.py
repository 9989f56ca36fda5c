"""A part's PrusaSlicer project: ``print/<part>.3mf``, the part in its print orientation with
support blockers over its tendon features, so that the grooves and channels print without
support.

With its automatic supports on, PrusaSlicer stands support in every tendon groove of the exported
STLs: a groove's floor is the pulley the cord bears on, and the half of it that faces down is a
curved overhang, each layer of which is a strip anchored on the groove's two flanks (1-1.9 mm
apart), which the slicer does not count as a bridge (docs/parts.md). Such support, in a 1 mm slot,
cannot be removed. Every overhang inside a tendon feature spans at most ``tendons.BRIDGE_MM``
between its walls (tests/export/test_project3mf.py measures it on the exported mesh), so the
project carries a support blocker over each (``Part.support_blockers``): PrusaSlicer then puts
support everywhere else it would, and none in them.

The file is a 3MF package (the 3MF core specification's model, one object) with PrusaSlicer's
volume table (``Metadata/Slic3r_PE_model.config``: each volume's triangle range and type;
``volume_type`` ``SupportBlocker``), which PrusaSlicer reads (2.5 here: the tests slice the
projects with it). The blockers are volumes of the part's one object, so a slicer that reads
only the 3MF core would take them for material: for any slicer but PrusaSlicer and its
descendants, the STL is the file. The project holds no print settings: the build's
``slicer/config.ini`` is loaded apart.
Deterministic: the same meshes give the same bytes (fixed zip dates and order).
"""

from __future__ import annotations

import io
import zipfile
from xml.sax.saxutils import quoteattr

import numpy as np

#: where the project places the part (bed mm, x and y of its bounding box's centre): PrusaSlicer
#: keeps a project's positions
BED_CENTRE = (100.0, 100.0)
#: the volume types PrusaSlicer reads from its volume table
MODEL_PART, SUPPORT_BLOCKER = "ModelPart", "SupportBlocker"

_CONTENT_TYPES = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
    '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
    '<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
    '<Default Extension="config" ContentType="text/xml"/>'
    '</Types>\n')
_RELS = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
    '<Relationship Target="/3D/3dmodel.model" Id="rel0" '
    'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>'
    '</Relationships>\n')
_VERTEX = '<vertex x="%.9g" y="%.9g" z="%.9g"/>\n'
_TRIANGLE = '<triangle v1="%d" v2="%d" v3="%d"/>\n'


def project_bytes(name: str, vertices: np.ndarray, faces: np.ndarray,
                  blockers: list[tuple[str, np.ndarray, np.ndarray]] = ()) -> bytes:
    """The 3MF of one part: its mesh (print frame, mm; written as float32, the STL's values) and
    its support blockers ((label, vertices, faces), the same frame), moved together so the part's
    bounding box is centred on :data:`BED_CENTRE`."""
    v = np.asarray(vertices, np.float32).astype(np.float64)
    lo, hi = v.min(axis=0), v.max(axis=0)
    shift = np.array([BED_CENTRE[0] - (lo[0] + hi[0]) / 2.0, BED_CENTRE[1] - (lo[1] + hi[1]) / 2.0, 0.0])
    volumes = [(name, MODEL_PART, v, np.asarray(faces, np.int64))]
    volumes += [(label, SUPPORT_BLOCKER, np.asarray(bv, float), np.asarray(bf, np.int64)) for label, bv, bf in blockers]
    vert_text, tri_text, table = [], [], []
    n_v = n_t = 0
    for label, kind, V, F in volumes:
        V = V + shift
        vert_text.append((_VERTEX * len(V)) % tuple(V.ravel().tolist()))
        tri_text.append((_TRIANGLE * len(F)) % tuple((F + n_v).ravel().tolist()))
        table.append((label, kind, n_t, n_t + len(F) - 1))
        n_v += len(V)
        n_t += len(F)
    model = (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<model unit="millimeter" xml:lang="en-US" '
        'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" '
        'xmlns:slic3rpe="http://schemas.slic3r.org/3mf/2017/06">\n'
        '<metadata name="slic3rpe:Version3mf">1</metadata>\n'
        f'<metadata name="Title">{_text(name)}</metadata>\n'
        '<resources>\n<object id="1" type="model">\n<mesh>\n<vertices>\n'
        + "".join(vert_text) + '</vertices>\n<triangles>\n' + "".join(tri_text)
        + '</triangles>\n</mesh>\n</object>\n</resources>\n'
        '<build>\n<item objectid="1" printable="1"/>\n</build>\n</model>\n')
    config = ['<?xml version="1.0" encoding="UTF-8"?>', '<config>', ' <object id="1" instances_count="1">',
              f'  <metadata type="object" key="name" value={quoteattr(name)}/>']
    for label, kind, first, last in table:
        config += [f'  <volume firstid="{first}" lastid="{last}">',
                   f'   <metadata type="volume" key="name" value={quoteattr(label)}/>']
        if kind != MODEL_PART:
            config.append('   <metadata type="volume" key="modifier" value="1"/>')
        config += [f'   <metadata type="volume" key="volume_type" value="{kind}"/>', '  </volume>']
    config += [' </object>', '</config>', '']
    return _zip([("[Content_Types].xml", _CONTENT_TYPES), ("_rels/.rels", _RELS),
                 ("3D/3dmodel.model", model), ("Metadata/Slic3r_PE_model.config", "\n".join(config))])


def _text(s: str) -> str:
    return quoteattr(s)[1:-1]


def _zip(members: list[tuple[str, str]]) -> bytes:
    """A zip of (name, text) members in this order, with fixed dates and attributes."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for name, text in members:
            info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            info.create_system = 3
            z.writestr(info, text.encode("utf-8"), compresslevel=1)   # 3x faster than 6, 25 % larger
    return buf.getvalue()
