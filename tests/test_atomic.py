"""Atomic writes: the whole new file or the old one, with the usual permissions."""

from __future__ import annotations

import os
import stat

import pytest

from phantom_cad.atomic import write_atomic, write_json_atomic


def test_write_text_bytes_and_json(tmp_path):
    write_atomic(tmp_path / "a" / "t.txt", "héllo\n")
    assert (tmp_path / "a" / "t.txt").read_bytes() == "héllo\n".encode("utf-8")
    write_atomic(tmp_path / "b.bin", b"\x00\x01")
    assert (tmp_path / "b.bin").read_bytes() == b"\x00\x01"
    write_json_atomic(tmp_path / "c.json", {"b": 1, "a": [1.5]}, indent=None, sort_keys=True)
    assert (tmp_path / "c.json").read_text() == '{"a": [1.5], "b": 1}\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "b.bin", "c.json"]   # no temporaries left


def test_permissions_follow_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        import importlib

        import phantom_cad.atomic as atomic

        importlib.reload(atomic)
        atomic.write_atomic(tmp_path / "f.txt", "x")
    finally:
        os.umask(old)
        importlib.reload(atomic)
    assert stat.S_IMODE((tmp_path / "f.txt").stat().st_mode) == 0o644   # not mkstemp's 0600


def test_a_failed_write_leaves_the_old_file(tmp_path):
    target = tmp_path / "keep.txt"
    target.write_text("old")
    with pytest.raises(TypeError):
        write_atomic(target, 12345)          # neither str nor bytes: fails while writing
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.txt"]


def test_replace_dir_swaps_a_finished_folder(tmp_path):
    from phantom_cad.atomic import replace_dir

    target = tmp_path / "out"
    target.mkdir()
    (target / "old.txt").write_text("old")
    stage = tmp_path / ".out.stage"
    stage.mkdir()
    (stage / "new.txt").write_text("new")
    replace_dir(stage, target)
    assert [p.name for p in target.iterdir()] == ["new.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]        # nothing set aside is left
    # a failing move puts the previous folder back
    stage2 = tmp_path / "missing-stage"
    with pytest.raises(FileNotFoundError):
        replace_dir(stage2, target)
    assert [p.name for p in target.iterdir()] == ["new.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_replace_dir_finishes_an_interrupted_swap(tmp_path):
    """A kill between the two renames of a swap must leave the old or the new export: the next
    swap finishes the interrupted one, and no hidden .out.old.* folder is left behind."""
    from phantom_cad.atomic import replace_dir

    target = tmp_path / "out"
    aside = tmp_path / ".out.old.abc123"
    (aside / "out").mkdir(parents=True)
    (aside / "out" / "old.txt").write_text("old")
    stale = tmp_path / ".out.old.zzz999"          # a second, older leftover
    (stale / "out").mkdir(parents=True)
    stage = tmp_path / ".out.stage"
    stage.mkdir()
    (stage / "new.txt").write_text("new")
    replace_dir(stage, target)
    assert [p.name for p in target.iterdir()] == ["new.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_replace_dir_refuses_a_concurrent_writer(tmp_path, monkeypatch):
    """Two commands swapping the same folder at once: the loser gets one clean error, its stage is
    removed, the winner's folder stays (was an OSError 'Directory not empty' traceback)."""
    import phantom_cad.atomic as atomic
    from phantom_cad.errors import UserError

    target = tmp_path / "out"
    stage = tmp_path / ".out.stage"
    stage.mkdir()
    (stage / "mine.txt").write_text("mine")
    real_rename = os.rename

    def racing_rename(src, dst):
        if str(src) == str(stage) and not target.exists():   # the other writer lands first
            target.mkdir()
            (target / "theirs.txt").write_text("theirs")
        return real_rename(src, dst)

    monkeypatch.setattr(atomic.os, "rename", racing_rename)
    with pytest.raises(UserError, match="could not be replaced"):
        atomic.replace_dir(stage, target)
    assert [p.name for p in target.iterdir()] == ["theirs.txt"]
    assert not stage.exists()
