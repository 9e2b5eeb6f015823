"""The Python example in README.md really runs."""

import re
import subprocess
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[2] / "README.md"


def test_readme_python_example_runs():
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "README.md has no ```python example"
    result = subprocess.run([sys.executable, "-c", blocks[0]], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip(), "the example printed nothing"


def test_readme_cpp_example_is_the_built_app():
    # `make test` builds and runs examples/cpp_app/main.cc against the installed package; the
    # README shows that same file, so the README example is what CI runs.
    blocks = re.findall(r"```cpp\n(.*?)```", README.read_text(), flags=re.S)
    main = (README.parent / "examples" / "cpp_app" / "main.cc").read_text()
    assert blocks and blocks[0] == main
