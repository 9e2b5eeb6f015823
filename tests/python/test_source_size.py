"""Files and functions small enough to hold in one's head (docs/architecture.md, issue 27): no
tracked source file above 600 lines and no function above 150, unless the file's header comment
(its first 30 lines) states why, naming the file's length ("600 lines") or the function (its name
and "150 lines").

Python functions are measured with ``ast``; C++ functions by their braces after comments, string
and character literals are removed (a definition at namespace scope whose statement has a
parameter list; members defined inside a class body are not measured).
"""

import ast
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MAX_FILE_LINES = 600
MAX_FUNCTION_LINES = 150
SOURCE_SUFFIXES = (".py", ".pyi", ".cc", ".h")


def _tracked_sources():
    try:
        out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
        names = out.split()
    except (OSError, subprocess.CalledProcessError):  # not a git checkout (an sdist): every file
        names = [str(p.relative_to(ROOT)) for p in ROOT.rglob("*") if p.is_file()]
    return sorted(ROOT / n for n in names if n.endswith(SOURCE_SUFFIXES) and (ROOT / n).is_file())


SOURCES = _tracked_sources()


def _header(path: Path) -> str:
    return "\n".join(path.read_text(errors="replace").splitlines()[:30])


def _python_functions(text: str):
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node.name, node.end_lineno - node.lineno + 1


def _strip_cpp(text: str) -> str:
    """Comments, string and character literals blanked (newlines kept)."""
    pattern = re.compile(r'//[^\n]*|/\*.*?\*/|R"(\w*)\(.*?\)\1"|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'', re.S)
    return pattern.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def _cpp_functions(text: str):
    """(name, lines) of each brace block opened at namespace scope by a statement with a parameter
    list (a function definition)."""
    text = _strip_cpp(text)
    scopes = []  # for each open brace: True when it is a namespace or extern block
    statement_start = 0
    opened_at = None
    for i, c in enumerate(text):
        if c == "{":
            head = text[statement_start:i]
            at_namespace_scope = all(scopes)
            is_namespace = re.search(r"\b(namespace|extern)\b[^;{}()]*$", head) is not None
            if at_namespace_scope and not is_namespace and opened_at is None and "(" in head and \
                    not re.search(r"\b(struct|class|enum|union)\b", head.split("(")[0]):
                name = re.findall(r"([\w:~]+)\s*\(", head)
                opened_at = (name[0] if name else "?", text.count("\n", 0, i), len(scopes))
            scopes.append(is_namespace)
            statement_start = i + 1
        elif c == "}":
            if scopes:
                scopes.pop()
            if opened_at is not None and len(scopes) == opened_at[2]:
                yield opened_at[0], text.count("\n", 0, i) - opened_at[1] + 1
                opened_at = None
            statement_start = i + 1
        elif c == ";":
            statement_start = i + 1


@pytest.mark.parametrize("path", SOURCES, ids=[str(p.relative_to(ROOT)) for p in SOURCES])
def test_file_and_functions_are_small_or_say_why(path):
    text = path.read_text(errors="replace")
    header = _header(path)
    lines = text.count("\n") + 1
    assert lines <= MAX_FILE_LINES or "600 lines" in header, (
        f"{path.relative_to(ROOT)}: {lines} lines (> {MAX_FILE_LINES}) and no reason in its header comment")
    functions = _python_functions(text) if path.suffix in (".py", ".pyi") else _cpp_functions(text)
    for name, length in functions:
        short = name.split("::")[-1]
        assert length <= MAX_FUNCTION_LINES or (short in header and "150 lines" in header), (
            f"{path.relative_to(ROOT)}: {name} has {length} lines (> {MAX_FUNCTION_LINES}) and no reason in the "
            "file's header comment")


def test_the_cpp_measure_finds_functions():
    """The brace scan measures a definition, skips namespaces, classes and literals."""
    text = 'namespace a {\nstruct S { int f() { return 1; } };\nint g(int x) {\n  const char* s = "}";\n' \
           '  if (x) {\n    return 2;\n  }\n  return 3;\n}\n}  // namespace a\n'
    assert list(_cpp_functions(text)) == [("g", 7)]
