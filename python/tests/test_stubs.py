"""The type stubs (python/polrig/_polrig.pyi) and the compiled module agree name for name, and
every public function, method and property carries a docstring beyond pybind11's signature."""
import ast
import inspect
import re

import polrig
from polrig import _polrig
from conftest import ROOT

STUBS = ROOT / "python" / "polrig" / "_polrig.pyi"
# Stub-only helpers (type aliases), not part of the module.
STUB_ALIASES = {"ArrayLike", "Array", "Progress"}


def stub_names():
    tree = ast.parse(STUBS.read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            top.add(node.name)
            members[node.name] = {
                n.target.id if isinstance(n, ast.AnnAssign) else n.name
                for n in node.body
                if isinstance(n, (ast.FunctionDef, ast.AnnAssign)) and
                (isinstance(n, ast.FunctionDef) or isinstance(n.target, ast.Name))
            }
        elif isinstance(node, ast.FunctionDef):
            top.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            top.add(node.target.id)
        elif isinstance(node, ast.Assign):
            top.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return top - STUB_ALIASES, members


def public(names):
    return {n for n in names if not n.startswith("_")}


def module_names():
    top = public(dir(_polrig)) | {"__version__"}
    members = {}
    for name in top:
        obj = getattr(_polrig, name)
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            members[name] = public(vars(obj))
    return top, members


def test_every_public_name_has_a_stub_and_every_stub_a_name():
    stub_top, stub_members = stub_names()
    mod_top, mod_members = module_names()
    assert sorted(mod_top - stub_top) == [], "in the module, missing from _polrig.pyi"
    assert sorted(stub_top - mod_top) == [], "in _polrig.pyi, not in the module"
    for cls, names in mod_members.items():
        declared = public(stub_members.get(cls, set()))
        assert sorted(names - declared) == [], f"{cls}: members missing from _polrig.pyi"
        assert sorted(declared - names) == [], f"{cls}: stub members not in the module"


def text_of(doc):
    """A docstring without pybind11's generated signature lines ("name(args) -> type")."""
    lines = [l for l in (doc or "").splitlines()
             if l.strip() and not re.match(r"^\s*(\d+\. )?\w+\(.*\)( -> .*)?$", l)
             and l.strip() != "Overloaded function."]
    return " ".join(lines).strip()


def test_every_public_callable_is_documented():
    undocumented = []
    for name in public(dir(_polrig)):
        obj = getattr(_polrig, name)
        if inspect.isclass(obj):
            if not text_of(obj.__doc__):
                undocumented.append(name)
            if issubclass(obj, BaseException):
                continue
            for member, value in vars(obj).items():
                if member.startswith("_"):
                    continue
                doc = value.__doc__ if not isinstance(value, (staticmethod, classmethod)) else value.__func__.__doc__
                if isinstance(value, property):
                    doc = value.__doc__
                if len(text_of(doc)) < 8:
                    undocumented.append(f"{name}.{member}")
        elif callable(obj) and len(text_of(obj.__doc__)) < 8:
            undocumented.append(name)
    assert undocumented == []


def test_the_package_reexports_the_module():
    assert set(polrig.__all__) == public(dir(_polrig)) - {"git_revision"}
    assert polrig.__version__ == _polrig.__version__


def split_params(text):
    """Top-level comma-separated parameters of a signature's parenthesised text -> names."""
    names, depth, cur = [], 0, ""
    for ch in text + ",":
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        if ch == "," and depth == 0:
            name = re.split(r"[:=]", cur.strip(), maxsplit=1)[0].strip()
            if name:
                names.append(name)
            cur = ""
        else:
            cur += ch
    return names


def module_signatures(doc, name):
    """Parameter-name lists of each pybind11 signature line "name(...) -> ..." of a docstring."""
    sigs = []
    for line in (doc or "").splitlines():
        m = re.match(rf"^\s*(?:\d+\. )?{re.escape(name)}\((.*)\)(?: -> .*)?$", line)
        if m:
            sigs.append(split_params(m.group(1)))
    return sigs


def stub_functions():
    """(owner, name, parameter names) of every def in the stubs ('' for module level)."""
    tree = ast.parse(STUBS.read_text())
    out = []

    def params(fn):
        a = fn.args
        names = [p.arg for p in a.posonlyargs + a.args]
        if a.vararg:
            names.append("*" + a.vararg.arg)
        elif a.kwonlyargs:
            names.append("*")
        names += [p.arg for p in a.kwonlyargs]
        return names

    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            out.append(("", node.name, params(node), node))
        elif isinstance(node, ast.ClassDef):
            for fn in node.body:
                if isinstance(fn, ast.FunctionDef):
                    out.append((node.name, fn.name, params(fn), fn))
    return out


def test_stub_signatures_name_the_modules_parameters():
    wrong = []
    for owner, name, stub_params, fn in stub_functions():
        if any(isinstance(d, ast.Name) and d.id == "property" for d in fn.decorator_list):
            continue
        obj = getattr(getattr(_polrig, owner) if owner else _polrig, name, None)
        if obj is None or (name.startswith("__") and name != "__init__"):
            continue
        sigs = module_signatures(obj.__doc__, name)
        if not sigs:
            continue  # not a pybind11 function (e.g. a Python-level attribute)
        if stub_params not in sigs:
            wrong.append(f"{owner + '.' if owner else ''}{name}: stub {stub_params}, module {sigs}")
    assert wrong == []
