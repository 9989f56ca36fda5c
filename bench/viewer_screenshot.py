"""Regenerate docs/img/viewer.png: ``phantom-cad view`` of the default hand in headless Chromium.

    .venv/bin/python bench/viewer_screenshot.py [--out docs/img/viewer.png] [--export DIR]

Starts the viewer (phantom_cad.cli.view.start_viewer) on a free localhost port against the
export DIR (default: a temporary folder, built with the part cache, $PHANTOM_CAD_CACHE or .cache:
about a second when the cache is warm, 1-2 minutes cold), sets the servos to 55 % of their
travel with the compensated model, opens the page in headless Chromium (/usr/bin/chromium and
/usr/bin/chromedriver: as root, bash .ci/sysdeps), waits until the software-rendered canvas
stops changing and saves a screenshot of the page.
"""

from __future__ import annotations

import argparse
import io
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--hide-scrollbars", "--window-size=1280,900")
#: the pose shown: this fraction of every servo's travel
FRACTION = 0.55


def settle(driver, timeout: float = 90.0) -> None:
    """Wait until two screenshots a second apart agree (the canvas stopped changing)."""
    import numpy as np
    from PIL import Image

    def shot():
        return np.asarray(Image.open(io.BytesIO(driver.get_screenshot_as_png())).convert("RGB"), dtype=int)

    end = time.monotonic() + timeout
    last = shot()
    while time.monotonic() < end:
        time.sleep(1.0)
        now = shot()
        if now.shape == last.shape and np.abs(now - last).max() <= 2:
            return
        last = now
    print("warning: the page did not settle; saving it anyway", file=sys.stderr)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "viewer.png")
    ap.add_argument("--export", type=Path, default=None, help="export folder (default: a temporary one)")
    args = ap.parse_args()

    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    import numpy as np

    from phantom_cad.cli.view import SLIDER_STEP, start_viewer
    from phantom_cad.kinematics.topology import SERVOS

    with tempfile.TemporaryDirectory() as tmp:
        export = args.export or Path(tmp) / "exports" / "phantom"
        viewer = start_viewer(None, export, host="127.0.0.1", port=0)
        hand = viewer.hand
        u = hand.u_min + FRACTION * (hand.u_max - hand.u_min)
        viewer.set_u(np.round(u / SLIDER_STEP) * SLIDER_STEP, compensated=True)   # on the sliders' grid
        opts = webdriver.ChromeOptions()
        opts.binary_location = CHROMIUM
        for flag in (*FLAGS, f"--user-data-dir={Path(tmp) / 'chromium'}"):
            opts.add_argument(flag)
        driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
        try:
            driver.get(viewer.url)
            WebDriverWait(driver, 60).until(
                lambda d: len(d.find_elements(By.CSS_SELECTOR, "[role=slider]")) == len(SERVOS))
            # the client's "software WebGL" notice is about this machine, not the viewer
            driver.execute_script("const s = document.createElement('style');"
                                  "s.textContent = '.mantine-Notifications-root { display: none !important; }';"
                                  "document.head.appendChild(s);")
            settle(driver)
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_bytes(driver.get_screenshot_as_png())
        finally:
            driver.quit()
            viewer.stop()
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
