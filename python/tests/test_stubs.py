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
