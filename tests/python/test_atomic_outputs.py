"""Every file the command line and the studies write is written atomically (never left
half-written): through ``indoorloc.io.atomic_file.write_text_atomic``, or a temporary file
renamed into place. A rule test over the sources, plus one command run end to end."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "python" / "indoorloc"
# A plain write is allowed only to a temporary file that is then renamed (its name says so).
PLAIN_WRITE = re.compile(r"(?<!tmp)\.write_text\(|\bopen\([^)]*,\s*[\"']w[\"']")


@pytest.mark.parametrize("folder", ["cli", "experiments"])
def test_outputs_are_written_atomically(folder):
    offenders = []
    for path in sorted((PACKAGE / folder).glob("*.py")):
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if PLAIN_WRITE.search(line) and "tmp" not in line:
                offenders.append(f"{path.name}:{number}: {line.strip()}")
    assert not offenders, "plain writes (use write_text_atomic):\n" + "\n".join(offenders)


def test_cli_json_survives_a_failed_write(tmp_path, monkeypatch):
    """A --json file that already exists is left whole when the new write fails midway."""
    from indoorloc.io import atomic_file

    target = tmp_path / "out.json"
    target.write_text(json.dumps({"old": True}))

    def failing_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(atomic_file.os, "replace", failing_replace)
    with pytest.raises(OSError):
        atomic_file.write_text_atomic(target, json.dumps({"new": True}))
    assert json.loads(target.read_text()) == {"old": True}
    assert [p.name for p in tmp_path.iterdir()] == ["out.json"]
