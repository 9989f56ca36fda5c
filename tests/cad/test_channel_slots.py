"""``common.channel_slots``: a channel that passes a cut less than a flank away runs into it by a
slot, worked by hand on boxes: 0.8 of the channel high (``common.SLOT_CHORD``), its faces crossing
the channel's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from phantom_cad.kinematics.vectors import nearest_on_box

pytest.importorskip("build123d")


def test_a_channel_passing_a_pocket_runs_into_it():
    """A channel of radius 0.5 along x from 0 to 20; a pocket x 8..12, y 1..4, z -2..2: 0.5 mm of
    wall where it passes (under a 0.8 mm flank) and under the flank where its distance to the
    pocket, hypot(dx, 1), is under 1.3: from x = 12 - sqrt(1.3^2 - 1) = 7.169 to 12.831. The slot
    runs a channel radius further each way, from the axis 2 (0.5 + 0.8) + 0.5 = 3.1 into the pocket,
    0.8 mm high (0.8 of the 1 mm channel). A pocket from y = 2 (1.5 mm of wall) gets none."""
    from phantom_cad.cad.parts.common import channel_slots

    reach = math.sqrt(1.3 ** 2 - 1.0)
    near = lambda pts: nearest_on_box(pts, (8.0, 1.0, -2.0), (12.0, 4.0, 2.0))     # noqa: E731
    far = lambda pts: nearest_on_box(pts, (8.0, 2.0, -2.0), (12.0, 4.0, 2.0))      # noqa: E731
    slots = channel_slots((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 20.0, 0.5, [near, far], 0.8)
    assert len(slots) == 1
    bb = slots[0].bounding_box()
    assert tuple(bb.min) == pytest.approx((8.0 - reach - 0.5, 0.0, -0.4), abs=0.05)
    assert tuple(bb.max) == pytest.approx((12.0 + reach + 0.5, 3.1, 0.4), abs=0.05)
    assert slots[0].volume == pytest.approx((4.0 + 2.0 * reach + 1.0) * 3.1 * 0.8, rel=0.02)


def test_a_channel_already_in_a_pocket_is_left_alone():
    from phantom_cad.cad.parts.common import channel_slots

    inside = lambda pts: nearest_on_box(pts, (8.0, -1.0, -2.0), (12.0, 4.0, 2.0))  # noqa: E731
    assert channel_slots(np.zeros(3), np.array([1.0, 0.0, 0.0]), 20.0, 0.5, [inside], 0.8) == []


def test_a_channel_beside_a_pocket_it_then_enters_runs_into_it_up_to_there():
    """The channel of radius 0.5 along x; a pocket whose part x 4..10, y 0.8..4 runs 0.3 mm of wall
    beside it and whose part x 10..12, y -1..4 it runs through. Beside, the wall is under the 0.8 mm
    flank from x = 4 - sqrt(1.3^2 - 0.8^2) = 2.975 (first sample 3.0) on to where the channel enters
    (last sample 9.95): one slot from 2.5 to 10.45, 3.1 toward +y. Where the pocket lies ahead or
    behind (its faces at x = 10 and 12, met square) nothing more."""
    from phantom_cad.cad.parts.common import channel_slots

    def pocket(pts):
        a, b = nearest_on_box(pts, (4.0, 0.8, -2.0), (10.0, 4.0, 2.0)), nearest_on_box(pts, (10.0, -1.0, -2.0), (12.0, 4.0, 2.0))
        k = b[0] < a[0]
        return np.where(k, b[0], a[0]), np.where(k[:, None], b[1], a[1])

    slots = channel_slots((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), 20.0, 0.5, [pocket], 0.8)
    assert len(slots) == 1
    bb = slots[0].bounding_box()
    assert tuple(bb.min) == pytest.approx((2.5, 0.0, -0.4), abs=1e-6)
    assert tuple(bb.max) == pytest.approx((10.45, 3.1, 0.4), abs=1e-6)
