"""Every option default is written once, in the C++ struct (CONVENTIONS rule 13).

- Every bound Options class has the one protocol of bindings/options_binding.h (kwargs
  constructor from the C++ defaults, replace, to_dict, validate, repr, ==, pickling).
- Its stub lists exactly its fields and restates no default.
- Every literal default a stub gives a function or method keyword equals the binding's, which is
  read from a default-constructed C++ struct where the keyword is an option field (bind_pdr.cc).
"""

import ast
import math
import pickle
import re
import types
import warnings
from pathlib import Path

import pytest

import indoorloc
from indoorloc import _core

STUBS = Path(indoorloc.__file__).parent / "_core"


def _options_classes():
    out = []
    for modname, sub in vars(_core).items():
        if not isinstance(sub, types.ModuleType):
            continue
        for name in dir(sub):
            obj = getattr(sub, name)
            if isinstance(obj, type) and name.endswith("Options"):
                out.append((modname, name, obj))
    return out


OPTIONS = _options_classes()


def test_every_options_class_is_found():
    names = {name for _, name, _ in OPTIONS}
    assert {"TrackerOptions", "GridTrackerOptions", "SmootherOptions", "FloorPlanOptions", "FilterOptions",
            "NetworkOptions", "SignalMapOptions", "ResamplingOptions"} <= names


@pytest.mark.parametrize("modname,name,cls", OPTIONS, ids=[n for _, n, _ in OPTIONS])
def test_options_protocol(modname, name, cls):
    default = cls()
    fields = default.to_dict()
    assert fields, f"{name} binds no field"
    default.validate()  # the C++ defaults are valid
    assert cls(**fields) == default
    assert pickle.loads(pickle.dumps(default)) == default
    assert repr(default).startswith(f"{name}(")
    # replace returns a changed copy and leaves the original alone.
    key, value = next((k, v) for k, v in fields.items() if isinstance(v, bool) or isinstance(v, (int, float)))
    if isinstance(value, bool):
        changed = default.replace(**{key: not value})
        assert getattr(changed, key) is (not value) and getattr(default, key) is value
    with pytest.raises(ValueError, match="is not a field of"):
        cls(no_such_field=1)
    with pytest.raises(TypeError, match=f"argument '{key}'"):
        cls(**{key: object()})


@pytest.mark.parametrize("modname,name,cls", OPTIONS, ids=[n for _, n, _ in OPTIONS])
def test_an_int_too_large_for_an_integer_field_is_a_value_error(modname, name, cls):
    # num_particles = 2**31 read "has the wrong type for TrackerOptions.num_particles: got int".
    ints = [k for k, v in cls().to_dict().items() if isinstance(v, int) and not isinstance(v, bool)]
    for key in ints:
        for value in (2**64, -(2**64)):
            with pytest.raises(ValueError, match=f"argument '{key}': {value} does not fit {name}.{key}"):
                cls(**{key: value})


def test_deprecated_positional_form_still_works():
    from indoorloc.fusion import SmootherOptions
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        o = SmootherOptions(50, 1000)
    assert any(issubclass(w.category, DeprecationWarning) for w in caught)
    assert o == SmootherOptions(num_trajectories=50, max_particles=1000)
    with pytest.raises(TypeError, match="given twice"):
        SmootherOptions(50, num_trajectories=60)


def _stub_tree(modname):
    return ast.parse((STUBS / f"{modname}.pyi").read_text())


@pytest.mark.parametrize("modname,name,cls", OPTIONS, ids=[n for _, n, _ in OPTIONS])
def test_options_stub_lists_the_fields_and_restates_no_default(modname, name, cls):
    node = next(n for n in _stub_tree(modname).body if isinstance(n, ast.ClassDef) and n.name == name)
    annotated = {s.target.id for s in node.body if isinstance(s, ast.AnnAssign) and isinstance(s.target, ast.Name)}
    assert annotated == set(cls().to_dict()), f"stub of {name}: fields differ from the binding's"
    init = next(f for f in node.body if isinstance(f, ast.FunctionDef) and f.name == "__init__")
    assert not init.args.defaults and not any(init.args.kw_defaults), f"stub of {name} restates defaults"


def _literal(node):
    try:
        return ast.literal_eval(node)
    except ValueError:
        return None


def _stub_literal_defaults():
    """(qualified name, argument, default) of every literal default in the stubs."""
    out = []
    for stub in sorted(STUBS.glob("*.pyi")):
        modname = stub.stem
        if not isinstance(getattr(_core, modname, None), types.ModuleType):
            continue
        for node in ast.parse(stub.read_text()).body:
            funcs = []
            if isinstance(node, ast.FunctionDef):
                funcs.append((node.name, node))
            elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):  # _x: stub-only bases
                funcs += [(f"{node.name}.{f.name}", f) for f in node.body if isinstance(f, ast.FunctionDef)]
            for qual, f in funcs:
                args = f.args.args[len(f.args.args) - len(f.args.defaults):]
                pairs = list(zip(args, f.args.defaults)) + list(zip(f.args.kwonlyargs, f.args.kw_defaults))
                for arg, default in pairs:
                    if default is None:
                        continue
                    if isinstance(default, ast.Constant) and default.value is Ellipsis:
                        continue  # the stub states no default
                    value = _literal(default)
                    if value is not None or (isinstance(default, ast.Constant) and default.value is None):
                        out.append((modname, qual, arg.arg, value))
    return out


def _split_top_level(text, sep=","):
    """Splits `text` at `sep` outside brackets and quotes."""
    parts, depth, quote, start = [], 0, None, 0
    for i, c in enumerate(text):
        if quote:
            quote = None if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c in "([{<":
            depth += 1
        elif c in ")]}>" and not (c == ">" and text[i - 1] == "-"):
            depth -= 1
        elif c == sep and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return parts


def _runtime_defaults(modname, qual):
    """{argument: default text} of the binding's (first) signature, from pybind11's docstring."""
    obj = getattr(_core, modname)
    for part in qual.split("."):
        obj = getattr(obj, part)
    name = qual.split(".")[-1]
    for line in (obj.__doc__ or "").splitlines():
        line = re.sub(r"^\d+\. ", "", line.strip())
        if not line.startswith(name + "("):
            continue
        inner = line[len(name) + 1:line.rindex(") -> ")]
        out = {}
        for item in _split_top_level(inner):
            pieces = [p.strip() for p in _split_top_level(item, "=")]
            arg = pieces[0].split(":")[0].strip()
            if len(pieces) == 2:
                out[arg] = pieces[1]
        return out
    raise AssertionError(f"{modname}.{qual}: no signature in the binding's docstring")


def _parse(text):
    return {"inf": math.inf, "-inf": -math.inf}.get(text) if text in ("inf", "-inf") else ast.literal_eval(text)


STUB_DEFAULTS = _stub_literal_defaults()


@pytest.mark.parametrize("modname,qual,arg,value", STUB_DEFAULTS,
                         ids=[f"{m}.{q}.{a}" for m, q, a, _ in STUB_DEFAULTS])
def test_stub_default_equals_the_binding(modname, qual, arg, value):
    defaults = _runtime_defaults(modname, qual)
    assert arg in defaults, f"{modname}.{qual}: the binding has no default for {arg!r} (the stub gives one)"
    runtime = _parse(defaults[arg])
    if isinstance(value, float) or isinstance(runtime, float):
        assert runtime == pytest.approx(value, rel=1e-12, abs=0.0), f"{modname}.{qual}({arg}=...)"
    else:
        assert runtime == value, f"{modname}.{qual}({arg}=...)"
