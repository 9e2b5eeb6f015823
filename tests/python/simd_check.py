"""Runs a script twice, with the library's AVX2 loops and without (INDOORLOC_DISABLE_AVX2), for
the tests that the two paths give the same bits."""
import os
import subprocess
import sys
from pathlib import Path
from typing import List, Sequence

import numpy as np


def outputs_with_and_without_avx2(script: str, tmp_path: Path, package_file: str,
                                  extra_args: Sequence[str] = ()) -> List[np.ndarray]:
    """The arrays `script` saves (run as ``python -c script OUT.npy *extra_args``, with the package
    that holds `package_file` on PYTHONPATH) with the AVX2 paths on and off, in that order."""
    # The folder holding the indoorloc package that `package_file` (a module of any depth) is in:
    # the subprocess then imports the same tree as the test, not an installed copy.
    src = str(next(p.parent for p in Path(package_file).resolve().parents if p.name == "indoorloc"))
    results = []
    for disable in ("0", "1"):
        path = tmp_path / f"avx2_off_{disable}.npy"
        env = dict(os.environ, INDOORLOC_DISABLE_AVX2=disable, PYTHONPATH=src)
        subprocess.run([sys.executable, "-c", script, str(path), *extra_args], check=True, env=env)
        results.append(np.load(path))
    return results
