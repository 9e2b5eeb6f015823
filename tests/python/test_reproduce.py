"""`indoorloc reproduce` (issue 18): cell statistics, the report builder, resume, and a tiny run
of every paper's section (``--quick --runs 2``)."""

from __future__ import annotations

import io
import json
import sys
import types

import numpy as np
import pytest

from indoorloc import cli, progress
from indoorloc.experiments import reproduce_report, reproduce_sections
from indoorloc.experiments.reproduce_cells import (
    VERDICT_ABOVE,
    VERDICT_BELOW,
    VERDICT_FEW_RUNS,
    VERDICT_INSIDE,
    VERDICT_NO_PAPER,
    Cell,
    Table,
    paper_percentile,
)


# --- cells -----------------------------------------------------------------------------------
def test_cell_statistics_and_verdicts():
    values = list(range(1, 101))  # 1..100
    s = Cell("r", "c", values, list(range(100)), paper=50.5, unit="m").summary()
    assert s["mean"] == pytest.approx(50.5) and s["median"] == pytest.approx(50.5)
    assert s["q1"] == pytest.approx(np.percentile(values, 25)) and s["q3"] == pytest.approx(np.percentile(values, 75))
    assert s["sd"] == pytest.approx(np.std(values, ddof=1))
    assert s["paper_percentile"] == pytest.approx(50.0) and s["verdict"] == VERDICT_INSIDE
    assert Cell("r", "c", values, list(range(100)), paper=99.0).summary()["verdict"] == VERDICT_ABOVE
    assert Cell("r", "c", values, list(range(100)), paper=2.0).summary()["verdict"] == VERDICT_BELOW
    assert Cell("r", "c", values, list(range(100))).summary()["verdict"] == VERDICT_NO_PAPER
    assert Cell("r", "c", [1.0, 2.0], [0, 1], paper=1.5).summary()["verdict"] == VERDICT_FEW_RUNS


def test_paper_percentile_counts_ties_half():
    assert paper_percentile(np.array([1.0, 2.0, 3.0, 4.0]), 2.0) == pytest.approx(37.5)
    assert paper_percentile(np.array([5.0, 5.0]), 5.0) == pytest.approx(50.0)
    assert paper_percentile(np.array([1.0, 2.0]), 0.0) == 0.0
    assert paper_percentile(np.array([1.0, 2.0]), 9.0) == 100.0


def test_cell_runs_without_value_are_counted_not_summarised():
    s = Cell("r", "c", [1.0, float("nan"), 3.0, 5.0, 7.0], [0, 1, 2, 3, 4], paper=4.0).summary()
    assert s["runs"] == 5 and s["runs_without_value"] == 1
    assert s["mean"] == pytest.approx(4.0) and s["values"][1] is None
    assert all(np.isfinite(v) for v in (s["mean"], s["sd"], s["q1"], s["q3"]))


def test_cell_rejects_seed_count_mismatch():
    with pytest.raises(ValueError, match="seeds"):
        Cell("r", "c", [1.0, 2.0], [0])


# --- report ----------------------------------------------------------------------------------
def _png(path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(2, 2))
    ax.plot([0, 1], [0, 1])
    fig.savefig(path)
    plt.close(fig)


def _fake_section(paper: str, tmp_path) -> dict:
    fig = tmp_path / "figures" / paper / "f.png"
    fig.parent.mkdir(parents=True, exist_ok=True)
    _png(fig)
    t = Table(paper, "Table 1", "a table", [Cell("row | a", "col", [1.0, 2.0, 3.0, 4.0], [0, 1, 2, 3], paper=2.5, unit="m",
                                                 note="a note"),
                                            Cell("row b", "col", [1.0, 2.0, 3.0, 4.0], [0, 1, 2, 3])],
              setup="how it ran")
    d = t.to_dict()
    d["figures"] = [f"figures/{paper}/f.png"]
    return {"paper": paper, "title": f"paper {paper} title", "seconds": 1.5, "settings": {}, "tables": [d]}


def test_report_markdown_html_json_agree(tmp_path):
    sections = [_fake_section("000", tmp_path), _fake_section("003", tmp_path)]
    paths = reproduce_report.write_report(tmp_path, sections, {"runs": 4, "seed": 0, "quick": False})
    md = paths["markdown"].read_text()
    assert "## Verdicts" in md and "## Paper 000: paper 000 title" in md and "### Table 1: a table" in md
    assert "row \\| a" in md  # a pipe inside a cell does not break the table
    assert "![f](figures/000/f.png)" in md and "*row | a / col*: a note" in md
    page = paths["html"].read_text()
    assert "data:image/png;base64," in page and "http://" not in page and "https://" not in page
    assert page.count("<img") == 2
    data = json.loads(paths["json"].read_text())
    assert data["schema_version"] == reproduce_report.SCHEMA_VERSION
    assert data["verdicts"]["000"] == {"inside": 1, "paper above": 0, "paper below": 0, "no paper figure": 1, "other": 0}
    cell = data["sections"][0]["tables"][0]["cells"][0]
    assert cell["values"] == [1.0, 2.0, 3.0, 4.0] and cell["paper"] == 2.5 and cell["verdict"] == VERDICT_INSIDE


# --- resume ----------------------------------------------------------------------------------
@pytest.fixture
def counting_section(monkeypatch):
    """A fake paper '000' whose module counts its runs."""
    module = types.ModuleType("indoorloc_test_fake_section")
    module.calls = 0

    def reproduce_tables(ctx):
        module.calls += 1
        runs = ctx.runs_or(5)
        return [Table("000", "T", "t", [Cell("r", "c", np.arange(runs, dtype=float), list(range(runs)), paper=1.0)])]

    module.reproduce_tables = reproduce_tables
    module.expected_seconds = lambda runs: 1.0
    monkeypatch.setitem(sys.modules, module.__name__, module)
    monkeypatch.setitem(reproduce_sections.SECTIONS, "000",
                        reproduce_sections.Section("000", "fake", module.__name__))
    return module


def test_finished_sections_are_kept_and_rerun_on_request(tmp_path, counting_section):
    settings = {"runs": 4, "seed": 0, "quick": False}
    first = reproduce_sections.run_all(["000"], tmp_path, settings, log=lambda m: None)
    assert counting_section.calls == 1 and not first["failed"]
    again = reproduce_sections.run_all(["000"], tmp_path, settings, log=lambda m: None)
    assert counting_section.calls == 1 and again["sections"] == first["sections"]
    reproduce_sections.run_all(["000"], tmp_path, settings, rerun=["000"], log=lambda m: None)
    assert counting_section.calls == 2
    # Other settings: the kept section does not count as finished.
    reproduce_sections.run_all(["000"], tmp_path, {**settings, "runs": 3}, log=lambda m: None)
    assert counting_section.calls == 3


def test_a_failing_section_is_reported_and_leaves_no_file(tmp_path, counting_section):
    def boom(ctx):
        raise RuntimeError("dataset broken")

    counting_section.reproduce_tables = boom
    res = reproduce_sections.run_all(["000"], tmp_path, {"runs": 2, "seed": 0, "quick": True}, log=lambda m: None)
    assert "dataset broken" in res["failed"]["000"] and not res["sections"]
    assert not reproduce_sections.section_path(tmp_path, "000").exists()


def test_unknown_paper_is_a_clear_error(tmp_path, capsys):
    assert cli.main(["reproduce", "--papers", "007", "--out", str(tmp_path)]) == 2
    assert "unknown paper" in capsys.readouterr().err
    assert cli.main(["reproduce", "--runs", "1", "--out", str(tmp_path)]) == 2
    assert "'--runs'" in capsys.readouterr().err


# --- progress lines when output is not a terminal ---------------------------------------------
def test_progress_prints_lines_when_not_a_terminal(monkeypatch):
    buf = io.StringIO()
    monkeypatch.setattr(sys, "stderr", buf)
    try:
        progress.configure(quiet=False, lines=True)
        assert progress.lines_enabled()
        assert list(progress.progress(range(3), desc="things")) == [0, 1, 2]
        with progress.stage("a part"):
            pass
        progress.configure(quiet=True, lines=True)
        list(progress.progress(range(3), desc="silent"))
    finally:
        progress.configure(quiet=False, lines=False)
    text = buf.getvalue()
    assert "things: 3 done in" in text and "a part: done in" in text and "silent" not in text


# --- a tiny run of every section --------------------------------------------------------------
PAPERS = ["000", "001", "002", "003", "004"]


def test_tiny_run_of_every_paper_writes_the_report(tmp_path, capsys):
    code = cli.main(["reproduce", "--quick", "--runs", "2", "--out", str(tmp_path), "--quiet", "--papers", *PAPERS])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    data = json.loads((tmp_path / "report.json").read_text())
    papers = [s["paper"] for s in data["sections"]]
    assert papers == PAPERS
    for s in data["sections"]:
        assert s["tables"], s["paper"]
        for t in s["tables"]:
            assert t["cells"], (s["paper"], t["name"])
            for c in t["cells"]:
                assert c["runs"] >= 1 and len(c["seeds"]) == c["runs"], (s["paper"], t["name"], c["row"])
                assert c["mean"] is not None and np.isfinite(c["mean"]), (s["paper"], t["name"], c["row"])
            for f in t["figures"]:
                assert (tmp_path / f).is_file()
    # Every section that has a paper figure reports where it falls.
    assert any(c["paper_percentile"] is not None for s in data["sections"] for t in s["tables"] for c in t["cells"])
    md = (tmp_path / "report.md").read_text()
    assert all(f"## Paper {p}" in md for p in papers)
    assert "data:image/png;base64," in (tmp_path / "report.html").read_text()
    # Resume: nothing runs again.
    assert cli.main(["reproduce", "--quick", "--runs", "2", "--out", str(tmp_path), "--papers", *PAPERS]) == 0
    assert "finished earlier" in capsys.readouterr().err
