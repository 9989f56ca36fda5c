"""Pictures and numbers of the walk-through in docs/effects.md ("From an unexplained residual to
your own effect"): runs its commands (docs/examples/servo_ripple/walkthrough.py) in a temporary
folder, copies the reports' pictures and draws what the calibrated control law does on the hand
with the hidden ripple. Run from the repository's root:
.venv/bin/python bench/walkthrough_figures.py [OUT_DIR]   (default docs/img)
"""

from __future__ import annotations

import importlib.util
import shutil
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
COPIES = {  # report picture -> docs picture
    "report_analytic/residual_before.png": "walkthrough_1_residual_analytic.png",
    "report_analytic/residual_after.png": "walkthrough_2_residual_library.png",
    "report_plugin/residual_after.png": "walkthrough_3_residual_plugin.png",
    "report_plugin/mae.png": "walkthrough_4_mae.png",
}


def walkthrough():
    spec = importlib.util.spec_from_file_location("walkthrough", ROOT / "docs/examples/servo_ripple/walkthrough.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main(out: Path) -> None:
    wt = walkthrough()
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        outputs = wt.run(tmp)
        for command, text in outputs.items():
            print(f"$ {command}\n{text}")
        for src, dst in COPIES.items():
            shutil.copyfile(Path(tmp) / src, out / dst)
            print(f"wrote {out / dst}")
        u, err_nominal, err_cal = wt.control_law_errors(Path(tmp) / "cal" / "calibrated.toml")
    joints = {2: "q3 index_dip", 3: "q4 index_pip", 4: "q5 index_mcp"}
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.6), sharey=True)
    for ax, err, label in ((axes[0], err_nominal, "nominal model's control law"),
                           (axes[1], err_cal, "calibrated file's control law (servo_ripple inverted)")):
        for j, name in joints.items():
            ax.plot(np.degrees(u), err[:, j], label=name)
        ax.axhline(0.0, color="k", lw=0.6)
        worst = np.abs(err[:, list(joints)]).max()
        ax.set_title(f"{label}\nlargest error {worst:.3f} deg", fontsize=9)
        ax.set_xlabel("u2 of the target pose (deg)")
        print(f"{label}: largest error on the index joints {worst:.4f} deg, "
              f"mean {np.abs(err[:, list(joints)]).mean():.4f} deg")
    axes[0].set_ylabel("reached - target (deg)")
    axes[0].legend(fontsize=8)
    fig.suptitle("index finger commanded to 181 poses along its travel; the hand has the hidden ripple", fontsize=10)
    fig.tight_layout()
    fig.savefig(out / "walkthrough_5_control_law.png", dpi=110)
    print(f"wrote {out / 'walkthrough_5_control_law.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "img")
