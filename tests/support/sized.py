"""A parameter document ``phantom-cad size`` writes, for tests that take one apart."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path


def sized_document(folder: Path, length: float, breadth: float) -> dict:
    """The document of ``phantom-cad size --hand-length LENGTH --hand-breadth BREADTH --no-search``
    (the reference's CMC placement scaled), written in ``folder``."""
    out = folder / f"sized_{length:g}x{breadth:g}.toml"
    run = subprocess.run([sys.executable, "-m", "phantom_cad", "size", "--hand-length", f"{length:g}",
                          "--hand-breadth", f"{breadth:g}", "--no-search", "--out", str(out)],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return tomllib.loads(out.read_text(encoding="utf-8"))
