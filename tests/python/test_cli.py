"""The indoorloc console script: --help, --version, demo (report with figures)."""

import os
import subprocess
import sys

import pytest

import indoorloc
from indoorloc import cli


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["--version"])
    assert exc.value.code == 0
    assert indoorloc.__version__ in capsys.readouterr().out
    with pytest.raises(SystemExit):
        cli.main(["--help"])
    assert "demo" in capsys.readouterr().out


def test_demo_writes_report_with_figures(tmp_path, capsys):
    assert cli.main(["demo", "--out", str(tmp_path), "--quiet", "--quick"]) == 0
    out = capsys.readouterr().out
    report = tmp_path / "report.md"
    assert str(report) in out
    text = report.read_text()
    assert "## Core: resampling schemes" in text
    assert "## WiFi: interpolated signal map" in text and "E_27 = 3.82 m" in text
    assert "## Map matching" in text and "## Analog HMM" in text and "## PDR" in text
    pngs = list(tmp_path.glob("*.png"))
    assert pngs and all(p.stat().st_size > 1000 for p in pngs)
    for p in pngs:
        assert f"({p.name})" in text


def test_unknown_demo_is_a_clear_error(tmp_path, capsys):
    assert cli.main(["demo", "--out", str(tmp_path), "--only", "nope"]) == 2
    assert "unknown demo" in capsys.readouterr().err


def test_missing_data_folder_is_a_clear_error(tmp_path, capsys):
    # A path that does not exist is the user's to fix: one line naming the argument, exit code 2.
    missing = tmp_path / "no_such_site"
    assert cli.main(["fusion", "evaluate", "--quiet", "--data-root", str(missing)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "data_root" in err and "Traceback" not in err


def test_console_script_entry_point_runs():
    # `python -m indoorloc` goes through the same main() as the console script.
    result = subprocess.run(
        [sys.executable, "-m", "indoorloc", "--version"],
        capture_output=True, text=True, env={**os.environ, "CI": "true"}, check=True,
    )
    assert result.stdout.strip() == f"indoorloc {indoorloc.__version__}"
