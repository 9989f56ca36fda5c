"""Atomic file writes (stdlib only): a reader sees the old file or the whole new one, never a part.

The data goes to a temporary file in the target's folder, which is then renamed over the target;
on any error the temporary file is removed and the target is left as it was.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any, Callable, Iterable

# mkstemp creates 0600 files; written files get the usual permissions (0666 less the umask)
_UMASK = os.umask(0)
os.umask(_UMASK)


def write_atomic(path: str | os.PathLike, data: str | bytes | Iterable[bytes]) -> None:
    """Write ``data`` (text as UTF-8, bytes, or pieces of bytes written one after the other) to
    ``path`` atomically, creating its folder."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            if isinstance(data, (str, bytes)):
                fh.write(data.encode("utf-8") if isinstance(data, str) else data)
            else:
                for piece in data:
                    fh.write(piece)
        os.chmod(tmp, 0o666 & ~_UMASK)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_json_atomic(path: str | os.PathLike, obj: Any, indent: int = 2, sort_keys: bool = False) -> None:
    write_atomic(path, json.dumps(obj, indent=indent, sort_keys=sort_keys) + "\n")


def check_writable(target: str | os.PathLike) -> None:
    """Refuse (UserError naming ``target``) an output path that cannot be written: a parent that is
    a file, a read-only or forbidden folder. Probed by creating and removing an empty folder in the
    nearest existing ancestor, so nothing is left behind; called before a command does its work."""
    from .errors import UserError

    target = Path(os.path.abspath(target))
    ancestor = target.parent
    while not os.path.lexists(ancestor) and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise UserError(f"{target}: cannot be written: {ancestor} is a file, not a folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=f".{target.name}.probe.", dir=ancestor))
    except OSError as exc:
        raise UserError(f"{target}: cannot be written ({exc.strerror} in {ancestor})") from None


def check_replaceable(target: str | os.PathLike, is_ours: Callable[[Path], bool], what: str) -> None:
    """Refuse (UserError naming the path) to replace ``target`` unless it does not exist, is an
    empty folder, or is an earlier output of the same kind (``is_ours(target)``, read from its
    marker file): a command never replaces a user's file or folder."""
    from .errors import UserError

    target = Path(target)
    check_writable(target)
    if not os.path.lexists(target):
        return
    if target.is_symlink() or not target.is_dir():
        raise UserError(f"{target}: exists and is not a folder; refusing to replace it with {what} "
                        "(choose another output path)")
    try:
        empty = not any(target.iterdir())
        ours = empty or is_ours(target)
    except OSError as exc:
        raise UserError(f"{target}: cannot be read ({exc.strerror}); refusing to replace it") from None
    if not ours:
        raise UserError(f"{target}: exists and is not {what} (its marker file is missing); refusing to "
                        "replace it (choose another output path, or remove the folder yourself)")


def check_file_replaceable(target: str | os.PathLike, marker: str, what: str) -> None:
    """Refuse (UserError naming the path) to write the file ``target`` unless it can be written and
    does not exist or is an earlier output of the same kind: its text starts with ``marker``."""
    from .errors import UserError

    target = Path(target)
    check_writable(target)
    if not os.path.lexists(target):
        return
    if target.is_dir():
        raise UserError(f"{target}: is a folder; {what} is written to a file (choose a file name)")
    try:
        with open(target, "rb") as fh:
            head = fh.read(len(marker.encode("utf-8")))
    except OSError as exc:
        raise UserError(f"{target}: cannot be read ({exc.strerror}); refusing to replace it") from None
    if head != marker.encode("utf-8"):
        raise UserError(f"{target}: exists and is not {what} (it does not start with {marker.strip()!r}); "
                        "refusing to replace it (choose another output path, or remove the file yourself)")


def replace_dir(stage: str | os.PathLike, target: str | os.PathLike) -> None:
    """Move the finished folder ``stage`` to ``target`` (a sibling). A previous ``target`` is set
    aside first and removed only once the new one is in place; if the move fails it is put back.
    A swap an earlier run left half done (killed between the two renames) is finished first."""
    from .errors import UserError

    stage, target = Path(stage), Path(target)
    recover_swaps(target)
    try:
        if not target.exists():
            os.rename(stage, target)
            return
        old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old.", dir=target.parent)) / target.name
        os.rename(target, old)
        try:
            os.rename(stage, target)
        except BaseException:
            os.rename(old, target)
            old.parent.rmdir()
            raise
    except OSError as exc:
        if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
            raise
        shutil.rmtree(stage, ignore_errors=True)
        raise UserError(f"{target}: could not be replaced ({exc.strerror}; another command writing it at "
                        "the same time?); nothing of this run was kept") from None
    shutil.rmtree(old.parent, ignore_errors=True)


def recover_swaps(target: str | os.PathLike) -> None:
    """Finish the swaps of ``target`` that were interrupted between their renames: the output set
    aside in ``.<name>.old.*/<name>`` is put back when nothing is at ``target``, and removed when a
    newer one is there."""
    target = Path(target)
    for aside in sorted(target.parent.glob(f".{target.name}.old.*")):
        old = aside / target.name
        if not os.path.lexists(target) and old.is_dir():
            os.rename(old, target)
        shutil.rmtree(aside, ignore_errors=True)
