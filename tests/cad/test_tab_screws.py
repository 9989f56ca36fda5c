"""The forearm module's tab screws on the palm's dorsal face (``Palm.tab_screws``): each pilot keeps
two perimeters from the palm's cuts, measured against OpenCascade's distance between the solids."""

from __future__ import annotations

import numpy as np
import pytest

from phantom_cad import units
from phantom_cad.cad.parts import palm as palm_module
from phantom_cad.cad.parts import wrist
from phantom_cad.cad.parts.palm import Palm
from phantom_cad.params import ParamError, load_params
from phantom_cad.params.rules import MIN_WALL

pytest.importorskip("build123d")


@pytest.fixture(scope="module")
def palm():
    return Palm(load_params("params/phantom.toml"))


def test_the_pilot_gap_is_opencascades_distance_to_the_cuts(palm):
    """The gap from a pilot at points along the tab, over the thumb drive and the thenar, against
    BRepExtrema's distance between the pilot's cylinder and the drives' channels and the thenar's
    cuts as the palm cuts them (to the sampling's 0.01 mm)."""
    from build123d import Compound
    from phantom_cad.cad.parts.common import cylinder, transform, turn_sphere

    t = palm.tol
    cuts = []
    for name, a, b, r in palm.drive_channels():
        cuts.append(turn_sphere(a, r, (0, 0, 1), (1, 0, 0)) if name.endswith("turn") else cylinder(a, b, r))
    cuts += [transform(tool, palm.T_cmc()) for tool in palm.thenar_tools()]
    cuts = Compound(cuts)
    (place, _), _ = wrist.tab_screw_places(palm.params)
    names = set()
    for dx in np.linspace(-20.0, 8.0, 8):
        c = place + np.array([dx, 0.0, 0.0])
        pilot = cylinder(c + np.array([0.0, 0.0, 1.0]), c - np.array([0.0, 0.0, t.screw_engagement]),
                         t.screw_pilot / 2.0)
        occ = pilot.distance_to(cuts)
        gap, name = palm.pilot_gap(c)
        names.add(name.split(" ")[0])
        assert gap == pytest.approx(occ, abs=0.01) if occ > 0.0 else gap <= 0.0
    assert {"thumb", "thenar's"} <= names                      # the sample meets both kinds of cut


def test_a_screw_stays_at_its_place_where_nothing_is_near(palm):
    screws = palm.tab_screws()
    for s, (place, _) in zip(screws, wrist.tab_screw_places(palm.params)):
        assert s == pytest.approx(place)
        assert palm.pilot_gap(s)[0] >= units.mm(MIN_WALL)


def test_a_screw_moves_in_off_a_cut_by_the_least_step(palm, monkeypatch):
    """A cut under the radial screw's place and the next four steps in: it moves five steps in."""
    (place, inward), _ = wrist.tab_screw_places(palm.params)
    real = Palm.pilot_gap

    def beside(self, c):
        if inward * (c[0] - place[0]) < 4.5 * palm_module.SCREW_STEP:
            return 0.1, "x"
        return real(self, c)

    monkeypatch.setattr(Palm, "pilot_gap", beside)
    assert palm.tab_screws()[0][0] == pytest.approx(place[0] + inward * 5 * palm_module.SCREW_STEP)


def test_no_place_that_clears_is_the_screws_error(palm, monkeypatch):
    monkeypatch.setattr(Palm, "pilot_gap", lambda self, c: (0.3, "thumb drive"))
    with pytest.raises(ParamError) as e:
        palm.tab_screws()
    text = str(e.value)
    assert "hardware.screw_diameter_mm" in text and "within 0.300 mm of the thumb drive" in text
