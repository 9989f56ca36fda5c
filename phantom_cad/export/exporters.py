"""The outputs of a build, one exporter each: the export pipeline runs :data:`EXPORTERS` in order
into its staging folder.

An :class:`Exporter` has a ``name``, says what it writes (``writes(ctx)``: paths relative to the
export folder) and writes it (``write(ctx, stage)``) from the :class:`ExportContext` of the build:
the parameters, the assembly interface, the part cache's entries (each part built, verified,
tessellated and drawn by the workers), the poses, the slicer's estimates. A new format is one
class here and one line in :data:`EXPORTERS`.

The list's order is the build's timing: the assembly STEP and its picture are finished in the
worker processes while the exporters before the first that needs them (``ctx.assembly_dir()``
waits for them) write the description, the BOM and the routing; the manifest comes last, as it
lists every file written before it.
"""

from __future__ import annotations

import abc
import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from ..cad.coupon import FitCoupon
from ..cad.gauge import AngleGauge
from ..cad.print_aids import AIDS
from ..kinematics.hand_params import HandParams
from . import cache as cache_mod

#: the robot description package's folder in an export
DESCRIPTION = "description"


@dataclass
class ExportContext:
    """What the exporters of one build read (``pipeline._Build.write`` makes it)."""

    params: HandParams
    params_path: Path
    asm: Any                        # the assembly interface (export.interface)
    names: list[str]
    keys: dict[str, str]            # part -> its cache key
    cache: cache_mod.Cache
    render: bool
    metas: dict[str, dict]          # part -> its cache entry's meta.json
    poses: dict[str, Any]           # part -> T_hand_link (mm)
    contacts: list
    interference: dict
    estimates: dict[str, dict | None]
    slicer_info: dict
    ini: str                        # slicer/config.ini
    aid_keys: dict[str, str]        # print aid kind -> its cache key
    aid_estimates: dict[str, dict | None]   # print aid kind -> PrusaSlicer's estimate (None: not sliced)
    #: waits for the assembly's workers and returns its cache folder (``pipeline._Build.assembly``)
    finish_assembly: Callable[[], Path]
    #: the manifest, once the Manifest exporter has written it
    manifest: dict | None = None
    _assembly_dir: Path | None = field(default=None, repr=False)
    _model: Any = field(default=None, repr=False)
    _bom: list | None = field(default=None, repr=False)
    _order: list | None = field(default=None, repr=False)

    def part_dir(self, name: str) -> Path:
        return self.cache.part_dir(self.keys[name])

    def aid_dir(self, aid) -> Path:
        return self.cache.aid_dir(aid, self.aid_keys[aid.kind])

    def assembly_dir(self) -> Path:
        """The assembly's cache folder (the STEP, the picture); the first call waits for the workers
        that make them."""
        if self._assembly_dir is None:
            self._assembly_dir = self.finish_assembly()
        return self._assembly_dir

    @property
    def has_description(self) -> bool:
        """Whether the assembly interface gives the fingertip frames a robot description needs
        (the stand-in of the pipeline tests does not)."""
        return hasattr(self.asm, "tip_frames")

    def robot_model(self):
        """The robot description's model (``export.robot``), made once."""
        if self._model is None:
            from .robot import robot_model

            self._model = robot_model(self.params, self.metas, self.asm.tip_frames(self.params), self.estimates)
        return self._model

    def bom(self) -> list[dict]:
        """assembly.bill_of_materials, made once: what the parts use (the manifest lists it, the
        order lines are made of it)."""
        if self._bom is None:
            self._bom = list(self.asm.bill_of_materials(self.params))
        return self._bom

    @property
    def sliced(self) -> bool:
        """Whether the slicer estimated every part."""
        return all(self.estimates.get(n) is not None for n in self.names)

    def order(self) -> list[dict]:
        """The orderable lines (cad.purchase) of :meth:`bom`, made once: the filament by the
        slicer's mass when sliced, else by the parts' estimated mass (manifest.mass_g)."""
        if self._order is None:
            from ..cad import purchase
            from .manifest import mass_g

            if self.sliced:
                grams = sum(self.estimates[n]["filament_g"] for n in self.names)
            else:
                grams = sum(mass_g(self.metas[n]["volume_mm3"], self.params.print) for n in self.names)
            self._order = purchase.order_lines(self.params, self.bom(), grams, self.sliced, tuple(self.names))
        return self._order


class Exporter(abc.ABC):
    """One output of a build (see the module doc)."""

    #: what it makes, in a word or two (logs, docs/exports.md)
    name: str = ""

    @abc.abstractmethod
    def writes(self, ctx: ExportContext) -> list[str]:
        """The files it writes for this build, relative to the export folder (posix)."""

    @abc.abstractmethod
    def write(self, ctx: ExportContext, stage: Path) -> None:
        """Write :meth:`writes` into ``stage`` (the export's staging folder)."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


def _copy(src: Path, stage: Path, rel: str) -> None:
    dst = stage / rel
    dst.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(src, dst)


class PartSolids(Exporter):
    """Each part's STEP (link frame) and STL (print orientation), from its cache entry."""

    name = "STEP/STL"

    def writes(self, ctx):
        return [f"{sub}/{n}.{sub}" for n in ctx.names for sub in ("step", "stl")]

    def write(self, ctx, stage):
        for sub in ("step", "stl"):
            (stage / sub).mkdir(exist_ok=True)
        for n in ctx.names:
            _copy(ctx.part_dir(n) / "part.step", stage, f"step/{n}.step")
            _copy(ctx.part_dir(n) / "part.stl", stage, f"stl/{n}.stl")


class PrintProjects(Exporter):
    """Each part's PrusaSlicer project (3MF with its support blockers, export/project3mf.py)."""

    name = "3MF projects"

    def writes(self, ctx):
        return [f"print/{n}.3mf" for n in ctx.names]

    def write(self, ctx, stage):
        (stage / "print").mkdir(exist_ok=True)
        for n in ctx.names:
            _copy(ctx.part_dir(n) / "part.3mf", stage, f"print/{n}.3mf")


class PartRenders(Exporter):
    """Each part's picture on the print bed (drawn by its worker)."""

    name = "part renders"

    def writes(self, ctx):
        return [f"renders/{n}.png" for n in ctx.names if ctx.render and (ctx.part_dir(n) / "render.png").is_file()]

    def write(self, ctx, stage):
        (stage / "renders").mkdir(exist_ok=True)
        for rel in self.writes(ctx):
            _copy(ctx.part_dir(Path(rel).stem) / "render.png", stage, rel)


class PrintAidFiles(Exporter):
    """A print aid (cad.print_aids): STEP, STL, the maker's sheet and its picture, in its folder;
    one subclass per aid."""

    @property
    @abc.abstractmethod
    def aid(self):
        """The aid's class (cad.print_aid.PrintAid)."""

    def writes(self, ctx):
        a = self.aid
        out = [f"{a.kind}/{f}" for f in cache_mod.aid_files(a)]
        if ctx.render and (ctx.aid_dir(a) / "render.png").is_file():
            out.append(f"{a.kind}/{a.name}.png")
        return out

    def write(self, ctx, stage):
        a = self.aid
        (stage / a.kind).mkdir()
        for f in cache_mod.aid_files(a):
            _copy(ctx.aid_dir(a) / f, stage, f"{a.kind}/{f}")
        if f"{a.kind}/{a.name}.png" in self.writes(ctx):
            _copy(ctx.aid_dir(a) / "render.png", stage, f"{a.kind}/{a.name}.png")


class Coupon(PrintAidFiles):
    """The fit-test coupon (cad.coupon)."""

    name = "fit coupon"
    aid = FitCoupon


class Gauge(PrintAidFiles):
    """The angle gauge (cad.gauge)."""

    name = "angle gauge"
    aid = AngleGauge


class SlicerConfig(Exporter):
    """The PrusaSlicer settings derived from params [print]."""

    name = "slicer config"

    def writes(self, ctx):
        return ["slicer/config.ini"]

    def write(self, ctx, stage):
        (stage / "slicer").mkdir(exist_ok=True)
        (stage / "slicer" / "config.ini").write_text(ctx.ini)


class _DescriptionPart(Exporter):
    """A piece of the robot description package (export/description.py), written when the assembly
    interface gives the fingertip frames."""

    def writes(self, ctx):
        if not ctx.has_description:
            return []
        from . import description

        return [f"{DESCRIPTION}/{rel}" for rel in self.files(ctx, description)]

    def write(self, ctx, stage):
        if ctx.has_description:
            self.write_into(ctx, stage / DESCRIPTION)

    @abc.abstractmethod
    def files(self, ctx, description) -> list[str]:
        """The files it writes, relative to the package folder."""

    @abc.abstractmethod
    def write_into(self, ctx, folder: Path) -> None:
        """Write them into the package folder ``folder``."""


class DescriptionMeshes(_DescriptionPart):
    """The description's visual and collision meshes (metres, link frames)."""

    name = "description meshes"

    def files(self, ctx, description):
        return description.mesh_files(ctx.robot_model())

    def write_into(self, ctx, folder):
        from . import description

        description.write_meshes(folder, ctx.robot_model(), {n: ctx.part_dir(n) for n in ctx.names})


class Urdf(_DescriptionPart):
    """The URDF, with package:// mesh URIs and with relative paths."""

    name = "URDF"

    def files(self, ctx, description):
        return description.urdf_files(ctx.robot_model())

    def write_into(self, ctx, folder):
        from . import description

        description.write_urdf(folder, ctx.robot_model())


class Mjcf(_DescriptionPart):
    """The MJCF (compiled by MuJoCo, cached) and its scene; after the meshes it reads."""

    name = "MJCF"

    def files(self, ctx, description):
        return description.mjcf_files(ctx.robot_model())

    def write_into(self, ctx, folder):
        from . import description

        description.write_mjcf(folder, ctx.robot_model(), {n: ctx.part_dir(n) for n in ctx.names}, ctx.cache)


class RosPackage(_DescriptionPart):
    """The ROS 2 package's own files: package.xml, CMakeLists.txt, README, LICENSE, CHANGELOG, the
    launch file and the RViz config."""

    name = "ROS 2 package"

    def files(self, ctx, description):
        return list(description.PACKAGE_FILES)

    def write_into(self, ctx, folder):
        from . import description

        description.write_package(folder, ctx.robot_model(), ctx.params.digest)


class RetargetingConfigs(_DescriptionPart):
    """The description's dex-retargeting configs (export/retargeting.py), on its local URDF."""

    name = "retargeting configs"

    def files(self, ctx, description):
        from . import retargeting

        return retargeting.config_files(ctx.robot_model())

    def write_into(self, ctx, folder):
        from . import description, retargeting

        model = ctx.robot_model()
        retargeting.write_configs(folder, model, description.urdf_files(model)[1])


class Bom(Exporter):
    """The orderable bill of materials (cad.purchase) as CSV."""

    name = "BOM"

    def writes(self, ctx):
        return ["bom.csv"]

    def write(self, ctx, stage):
        from .bom import bom_csv

        (stage / "bom.csv").write_text(bom_csv(ctx.order()), encoding="utf-8")


class BomMarkdown(Exporter):
    """The orderable bill of materials by category, with the totals and the assembly list, as
    Markdown."""

    name = "BOM (Markdown)"

    def writes(self, ctx):
        return ["bom.md"]

    def write(self, ctx, stage):
        from .bom import bom_md

        (stage / "bom.md").write_text(bom_md(ctx.order(), ctx.bom(), ctx.params.name, ctx.sliced),
                                       encoding="utf-8")


class Routing(Exporter):
    """kinematics.routing_json.document: every tendon's strands and path elements."""

    name = "routing"

    def writes(self, ctx):
        return ["routing.json"]

    def write(self, ctx, stage):
        from ..kinematics import routing_json

        (stage / "routing.json").write_text(json.dumps(routing_json.document(ctx.params), indent=1) + "\n",
                                            encoding="utf-8")


class AssemblyStep(Exporter):
    """Every part placed at the rest pose, one STEP (made in the workers)."""

    name = "assembly STEP"

    def writes(self, ctx):
        return ["step/hand_assembly.step"]

    def write(self, ctx, stage):
        _copy(ctx.assembly_dir() / "hand_assembly.step", stage, "step/hand_assembly.step")


class AssemblyRender(Exporter):
    """The assembled hand's picture (drawn in the workers)."""

    name = "assembly render"

    def writes(self, ctx):
        return ["renders/hand_assembly.png"] if ctx.render else []

    def write(self, ctx, stage):
        if ctx.render and (ctx.assembly_dir() / "render.png").is_file():
            _copy(ctx.assembly_dir() / "render.png", stage, "renders/hand_assembly.png")


class Manifest(Exporter):
    """manifest.json: what was built from what, every file written before it with its checksum
    (export/manifest.py)."""

    name = "manifest"

    def writes(self, ctx):
        return ["manifest.json"]

    def write(self, ctx, stage):
        from . import manifest as manifest_mod

        man = manifest_mod.build_manifest(
            stage=stage, params=ctx.params, params_path=ctx.params_path, names=ctx.names, keys=ctx.keys,
            metas=ctx.metas, poses=ctx.poses, estimates=ctx.estimates, slicer_info=ctx.slicer_info,
            interference=ctx.interference, contacts=ctx.contacts, bom=ctx.bom())
        for aid in AIDS:
            meta = json.loads((ctx.aid_dir(aid) / "meta.json").read_text(encoding="utf-8"))
            base = f"{aid.kind}/{aid.name}"
            man[aid.kind] = {"step": f"{base}.step", "stl": f"{base}.stl", "sheet": f"{base}.md",
                             **{k: meta[k] for k in ("volume_mm3", "mass_g", "bbox_mm", *aid.listed)},
                             "print": ctx.aid_estimates[aid.kind]}
        if ctx.has_description:
            from .description import summary

            man["description"] = summary(ctx.robot_model(), DESCRIPTION)
        (stage / "manifest.json").write_text(json.dumps(man, indent=1, sort_keys=False) + "\n")
        ctx.manifest = man


#: every output of a build, in the order the pipeline writes them (see the module doc)
EXPORTERS: tuple[Exporter, ...] = (
    PartSolids(), PrintProjects(), PartRenders(), Coupon(), Gauge(), SlicerConfig(),
    DescriptionMeshes(), Urdf(), Mjcf(), RosPackage(), Bom(), BomMarkdown(), Routing(),
    AssemblyStep(), AssemblyRender(),
    RetargetingConfigs(),
    Manifest(),
)
