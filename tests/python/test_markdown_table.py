"""The studies' titled Markdown table (experiments.markdown_table)."""

from indoorloc.experiments.markdown_table import titled_table


def test_titled_table_has_title_header_rule_and_one_line_per_row():
    text = titled_table("Errors", ["method", "mean [m]"], [["knn", "1.50"], ["grid", "0.90"]])
    assert text.split("\n") == ["**Errors**", "", "| method | mean [m] |", "|---|---|",
                                "| knn | 1.50 |", "| grid | 0.90 |"]


def test_titled_table_without_rows_is_the_header_alone():
    assert titled_table("T", ["a"], []) == "**T**\n\n| a |\n|---|"
