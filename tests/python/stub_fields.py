"""The annotated fields of the classes of a binding stub (``indoorloc/_core/*.pyi``), for the tests
that check a typed result's stub against its bound fields (``type(result)._fields``)."""

import ast
from pathlib import Path

import indoorloc


def stub_fields(stub_name):
    """{class name: its annotated field names, those of its bases defined in the same stub first}
    for every class of ``indoorloc/_core/<stub_name>`` (e.g. ``"fusion.pyi"``)."""
    tree = ast.parse((Path(indoorloc.__file__).parent / "_core" / stub_name).read_text())
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}

    def fields(node):
        inherited = [f for b in node.bases if isinstance(b, ast.Name) and b.id in classes for f in fields(classes[b.id])]
        return inherited + [s.target.id for s in node.body if isinstance(s, ast.AnnAssign)]

    return {name: fields(node) for name, node in classes.items()}
