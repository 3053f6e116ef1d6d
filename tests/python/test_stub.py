"""The committed type stub is the one tools/make_stub.py makes from the module, and covers it all."""

import ast
import contextlib
import io
import os
import sys

import novaphy._novaphy as module

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tools"))

import make_stub  # noqa: E402


def test_stub_is_up_to_date():
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        make_stub.main()
    with open(os.path.join(ROOT, "bindings", "python", "novaphy", "_novaphy.pyi")) as f:
        committed = f.read()
    assert out.getvalue() == committed, "run: PYTHONPATH=build/python python3 tools/make_stub.py > bindings/python/novaphy/_novaphy.pyi"


def test_stub_names_every_public_class_and_function():
    with open(os.path.join(ROOT, "bindings", "python", "novaphy", "_novaphy.pyi")) as f:
        tree = ast.parse(f.read())
    stubbed = {node.name for node in tree.body if isinstance(node, (ast.ClassDef, ast.FunctionDef))}
    public = {name for name in vars(module) if not name.startswith("_")}
    assert public == stubbed
