"""The typed stubs of indoorloc._core list exactly the public names of the compiled module."""

import ast
import types
from pathlib import Path

import indoorloc
from indoorloc import _core

STUBS = Path(indoorloc.__file__).parent / "_core"


def _stub_names(path: Path) -> set:
    tree = ast.parse(path.read_text())
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return {n for n in names if not n.startswith("_")}


def test_py_typed_marker_is_shipped():
    assert (Path(indoorloc.__file__).parent / "py.typed").exists()


def test_each_submodule_has_a_stub_matching_its_names():
    for name, sub in vars(_core).items():
        if not isinstance(sub, types.ModuleType):
            continue
        stub = STUBS / f"{name}.pyi"
        assert stub.exists(), f"missing stub {stub}"
        runtime = {n for n in dir(sub) if not n.startswith("_")}
        assert _stub_names(stub) == runtime, f"stub {stub.name} out of sync"
