"""Every option default is written once, in the C++ struct (CONVENTIONS rule 13).

- Every bound Options class has the one protocol of bindings/options_binding.h (kwargs
  constructor from the C++ defaults, replace, to_dict, validate, repr, ==, pickling).
- Its stub lists exactly its fields and restates no default.
- Every literal default a stub gives a function or method keyword equals the binding's, which is
  read from a default-constructed C++ struct where the keyword is an option field.
- Every bound Options default equals the one written in its C++ header (read from the header's
  text, so that a binding that set a field of its own would be caught).
"""

import ast
import math
import pickle
import re
import types
import warnings
from pathlib import Path

import numpy as np
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
    # __init__ in the class or in a stub-only base (``class ZuptEkfOptions(_Options)``).
    classes = {n.name: n for n in _stub_tree(modname).body if isinstance(n, ast.ClassDef)}
    bodies = [node.body] + [classes[b.id].body for b in node.bases
                            if isinstance(b, ast.Name) and b.id.startswith("_") and b.id in classes]
    init = next(f for body in bodies for f in body if isinstance(f, ast.FunctionDef) and f.name == "__init__")
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


# ------------------------------------------------------------------ defaults against the headers

HEADERS = Path(__file__).resolve().parents[2] / "cpp" / "include" / "indoorloc"


def _struct_statements(name):
    """The member statements (``type field = value``) at the top level of ``struct name``."""
    for header in sorted(HEADERS.glob("*/*.h")):
        text = re.sub(r"//[^\n]*|/\*.*?\*/", "", header.read_text(), flags=re.S)
        m = re.search(rf"\bstruct {name}\s*\{{", text)
        if not m:
            continue
        out, depth, start = [], 1, m.end()
        for i in range(m.end(), len(text)):
            c = text[i]
            if c in "{([":
                depth += 1
            elif c in "})]":
                depth -= 1
                if depth == 0:
                    return out
            elif c == ";" and depth == 1:
                out.append(" ".join(text[start:i].split()))
                start = i + 1
            if c in "})]" and depth == 1:
                start = start  # a nested initializer ended inside the statement; keep collecting
        return out
    return None


class _Enumerator(str):
    """An enumerator default (``Type::kHeadingAware``): equal to the binding's string when they
    read the same without underscores and case (``"heading_aware"``)."""

    def matches(self, bound) -> bool:
        return isinstance(bound, str) and bound.replace("_", "").lower() == self.lower()


def _cpp_value(expr):
    """A C++ literal, an arithmetic of literals (M_PI allowed), an enumerator or a brace list of
    literals as a Python value; None for anything else."""
    expr = expr.replace("'", "").strip()
    expr = re.sub(r"std::numeric_limits<double>::infinity\(\)", "inf", expr)
    if expr in ("true", "false"):
        return expr == "true"
    enumerator = re.fullmatch(r"(?:\w+::)+k(\w+)", expr)
    if enumerator:
        return _Enumerator(enumerator.group(1))
    if expr.startswith("{") and expr.endswith("}"):
        items = [_cpp_value(e) for e in expr[1:-1].split(",")]
        return None if any(i is None or isinstance(i, (bool, str)) for i in items) else items
    expr = expr.replace("M_PI", "3.141592653589793")
    if not re.fullmatch(r"[-+*/(). 0-9eEinf]+", expr) or re.search(r"[a-df-hj-z]", expr.replace("inf", "")):
        return None
    try:
        return eval(expr.replace("inf", "float('inf')"), {"__builtins__": {"float": float}})
    except Exception:  # noqa: BLE001 - not an expression of literals
        return None


def _header_defaults(name):
    """{field: default} of ``struct name`` read from its header; None when no header has it."""
    statements = _struct_statements(name)
    if statements is None:
        return None
    out = {}
    for st in statements:
        m = re.fullmatch(r"(?:[\w:<>,]+\s+)+(\w+)(?:\[\d+\])?\s*=\s*(.+)", st)
        if m and "(" not in m.group(1):
            value = _cpp_value(m.group(2))
            if value is not None:
                out[m.group(1)] = value
    return out


def _nested_members(name):
    """[(member, its defaults)] of the members of ``struct name`` that are structs of the headers:
    the nested struct's own defaults, overridden by the member's initializer (``fix{0.01, 1.0}``
    in the nested struct's field order, or a lambda's ``o.threshold = 1e4;``)."""
    out = []
    for st in _struct_statements(name) or []:
        m = re.fullmatch(r"(?:\w+::)*(\w+)\s+(\w+)\s*(.*)", st, flags=re.S)
        if not m or not m.group(1)[0].isupper() or _struct_statements(m.group(1)) is None:
            continue
        defaults = dict(_header_defaults(m.group(1)) or {})
        init = m.group(3).strip()
        if init.startswith("{"):
            fields = [re.fullmatch(r"(?:[\w:<>,]+\s+)+(\w+)(?:\s*=.*)?", f) for f in _struct_statements(m.group(1))]
            names = [f.group(1) for f in fields if f]
            for field, text in zip(names, init.strip("{}").split(",")):
                value = _cpp_value(text)
                if value is not None:
                    defaults[field] = value
        for field, text in re.findall(r"\w+\.(\w+)\s*=\s*([^;]+);", init):
            value = _cpp_value(text)
            defaults[field] = value
        out.append((m.group(2), {k: v for k, v in defaults.items() if v is not None}))
    return out


def _bound_header_defaults(name, bound):
    """{bound field: header default}: the struct's own literal defaults, and those of its nested
    Options the binding flattens (``fix_tempering`` or ``tempering`` for ``fix.tempering``)."""
    own = _header_defaults(name)
    if own is None:
        return None
    out = {k: v for k, v in own.items() if k in bound}
    for member, defaults in _nested_members(name):
        for sub, value in defaults.items():
            for key in (f"{member}_{sub}", sub):
                if key in bound and key not in out and key not in own:
                    out[key] = value
                    break
    return out


@pytest.mark.parametrize("modname,name,cls", OPTIONS, ids=[n for _, n, _ in OPTIONS])
def test_bound_defaults_equal_the_cpp_header(modname, name, cls):
    bound = cls().to_dict()
    checked = _bound_header_defaults(name, bound)
    if checked is None:
        pytest.skip(f"{name} is not a struct of cpp/include/indoorloc (a binding-side class)")
    assert checked, f"{name}: no field of the binding has a literal default in its header"
    for key, value in checked.items():
        if isinstance(value, _Enumerator):
            assert value.matches(bound[key]), f"{name}.{key}: binding {bound[key]!r}, header enumerator k{value}"
        elif isinstance(value, bool) or isinstance(bound[key], bool):
            assert bound[key] is value, f"{name}.{key}: binding {bound[key]!r}, header {value!r}"
        else:
            assert list(np.atleast_1d(bound[key])) == pytest.approx(list(np.atleast_1d(value)), rel=1e-12, abs=0.0), (
                f"{name}.{key}: binding {bound[key]!r}, header {value!r}")


#: Bound fields whose default is no literal of a header: nested Options objects (checked as
#: classes of their own) and the resampling scheme a class names after its member.
NOT_LITERAL = {("FingerprintFixOptions", "matcher"), ("LiveSessionOptions", "detector"),
               ("FilterOptions", "resampling"), ("TrackerOptions", "resampling")}


def test_every_bound_default_is_checked_against_a_header():
    """The header check above reaches every bound field but the few listed in NOT_LITERAL."""
    missing = []
    for _, name, cls in OPTIONS:
        bound = cls().to_dict()
        checked = _bound_header_defaults(name, bound)
        if checked is None:
            continue
        missing += [(name, k) for k in bound if k not in checked and (name, k) not in NOT_LITERAL]
    assert not missing, f"bound option defaults not found in the headers: {missing}"
