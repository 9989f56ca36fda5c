"""Do two checkouts export the same hands? Build the default, left and 170 mm hands, or compare two
such sets file by file through their manifests.

    python bench/compare_exports.py build OUT          # OUT/default, OUT/left, OUT/hand_length_170
    python bench/compare_exports.py compare OLD NEW    # exit 0 when every file's SHA-256 agrees

`build` runs this checkout's `phantom-cad build` with a part cache of
its own, so nothing an earlier build cached is served. `compare` reads each manifest's ``files``
table (path -> SHA-256) and the manifest itself with the fields that name the code left out (its
``code_digest``, the package's version string and each part's ``cache_key``, which hashes the code
digest in), and prints every difference.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: (folder, parameter file, extra build arguments)
HANDS = (
    ("default", "params/phantom.toml", ()),
    ("left", "params/phantom.toml", ("--side", "left")),
    ("hand_length_170", "params/examples/small.toml", ()),
)

#: manifest fields that name the code that wrote it, not what it wrote
CODE_FIELDS = (("code_digest",), ("versions", "phantom_cad"))


def build(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "PHANTOM_CAD_CACHE": cache, "PYTHONPATH": str(ROOT)}
        for name, params, extra in HANDS:
            cmd = [sys.executable, "-c", "import sys; from phantom_cad.cli import main; sys.exit(main())", "build", "--params", str(ROOT / params),
                   "--out", str(out / name), *extra]
            print("$", " ".join(cmd), flush=True)
            subprocess.run(cmd, check=True, cwd=ROOT, env=env)


def _manifest(folder: Path) -> dict:
    man = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    for path in CODE_FIELDS:
        node = man
        for key in path[:-1]:
            node = node.get(key, {})
        node.pop(path[-1], None)
    for part in man.get("parts", ()):
        part.pop("cache_key", None)
    return man


def compare(old: Path, new: Path) -> int:
    differences = 0
    for name, _, _ in HANDS:
        a, b = _manifest(old / name), _manifest(new / name)
        fa, fb = a.pop("files"), b.pop("files")
        for rel in sorted(set(fa) | set(fb)):
            sa, sb = fa.get(rel, {}).get("sha256"), fb.get(rel, {}).get("sha256")
            if sa != sb:
                differences += 1
                print(f"{name}/{rel}: {sa} -> {sb}")
        if a != b:
            differences += 1
            keys = sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))
            print(f"{name}/manifest.json differs in {', '.join(keys)}")
        print(f"{name}: {len(fa)} files compared", flush=True)
    print("same" if not differences else f"{differences} differences")
    return 1 if differences else 0


def main(argv: list[str]) -> int:
    if len(argv) == 2 and argv[0] == "build":
        build(Path(argv[1]).resolve())
        return 0
    if len(argv) == 3 and argv[0] == "compare":
        return compare(Path(argv[1]), Path(argv[2]))
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
