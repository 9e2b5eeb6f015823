"""io.atomic_file: a written file replaces the target in one rename, gets ordinary permissions
(0666 less the umask, not mkstemp's 0600), and a failed write leaves the old file and no
temporary file behind."""

import os

import pytest

from indoorloc.io.atomic_file import write_text_atomic


def test_written_with_ordinary_permissions_and_replaced_whole(tmp_path):
    target = tmp_path / "sub" / "track.geojson"
    old = os.umask(0o022)
    try:
        write_text_atomic(target, "first\n")
        assert target.read_text() == "first\n"
        assert (target.stat().st_mode & 0o777) == 0o644
        write_text_atomic(target, "second\n")
        assert target.read_text() == "second\n"
    finally:
        os.umask(old)
    assert [p.name for p in target.parent.iterdir()] == ["track.geojson"]


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "out.csv"
    target.write_text("kept\n")
    with pytest.raises(UnicodeEncodeError):
        write_text_atomic(target, "\udcff not encodable", encoding="utf-8")
    assert target.read_text() == "kept\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]
