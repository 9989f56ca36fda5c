"""The ``phantom-cad retarget`` command (registered by phantom_cad/cli/__init__.py): human hand
keypoints onto the six servos through dex-retargeting, the coupling and the control law
(``phantom_cad.retargeting``; docs/retargeting.md). Builds no geometry: imports no CAD library.

Exit codes: 0 written; 2 bad input (one ``error:`` line: a missing file, keypoints of the wrong
shape, frames with NaN keypoints, dex-retargeting not installed)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer


def retarget(
    keypoints: Path = typer.Argument(..., help="Keypoints: .npy of shape (frames, 21, 3), or a CSV of 63 columns "
                                     "(x, y, z of MediaPipe's 21 hand landmarks in order) or 64 (a time first).",
                                     dir_okay=False),
    out: Path = typer.Option(..., "--out", help="CSV to write: per frame u1..u6 (deg) and the joint error the "
                             "coupling leaves (deg).", dir_okay=False),
    params: Optional[Path] = typer.Option(None, "--params", "-p", help="Parameter file (default: "
                                          "params/phantom.toml).", dir_okay=False),
    method: str = typer.Option("vector", "--method", help="dex-retargeting's method: vector (teleoperation) or "
                               "position (every joint at its keypoint)."),
    side: Optional[str] = typer.Option(None, "--side", help="The human hand's side, right or left (default: the "
                                       "parameter file's hand.side): a left hand drives the mirrored hand."),
) -> None:
    """Retarget a sequence of human hand keypoints onto the hand: dex-retargeting's 15 joint angles
    (the description package's config), projected through the coupling and the control law onto
    the six servos within their travel; per frame the commands and the joint error the coupling
    cannot follow."""
    import numpy as np

    from .. import make_hand
    from .. import retargeting as R
    from ..errors import UserError
    from ..kinematics.topology import JOINT_NAMES
    from ..units import deg
    from .calibration import CSV_MARKER, check_output

    if method not in R.RC.METHODS:
        raise UserError(f"retarget: --method {method!r}: must be one of {', '.join(R.RC.METHODS)}")
    if side is not None and side not in ("right", "left"):
        raise UserError(f"retarget: --side {side!r}: must be right or left")
    check_output(out, CSV_MARKER, "a CSV written by phantom-cad")
    points, times = R.read_keypoints(keypoints)
    p = R.load_params(params, side)
    result = R.retarget(make_hand(p), points, method)
    R.write_commands(out, result, times, f"phantom-cad retarget --method {method}, {p.name} hand ({p.side}), "
                                         f"params digest {p.digest[:12]}, degrees")
    worst = np.unravel_index(int(np.argmax(np.abs(result.error))), result.error.shape)
    typer.echo(f"wrote {len(points)} frames to {out}: {method} retargeting onto the {p.name} hand ({p.side})")
    typer.echo(f"joint error the coupling leaves: median of the frames' largest {deg(np.median(result.max_error)):.1f} "
               f"deg, worst {deg(result.max_error.max()):.1f} deg ({JOINT_NAMES[worst[1]]}, frame {worst[0]})")
