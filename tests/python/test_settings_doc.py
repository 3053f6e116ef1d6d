"""The settings table drives the binding and the reference page: every setting is bound with its default
and doc, and the committed docs/settings.md is the page tools/make_settings_doc.py writes from the module."""

import os
import subprocess
import sys

import pytest

import novaphy.solvers

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")


def test_settings_page_is_up_to_date():
    written = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "make_settings_doc.py")],
                             capture_output=True, text=True, check=True).stdout
    with open(os.path.join(ROOT, "docs", "settings.md")) as page:
        assert written == page.read(), "run: PYTHONPATH=build/python python3 tools/make_settings_doc.py > docs/settings.md"


@pytest.mark.parametrize("solver, least", [("SolverFeatherstone", 22), ("SolverSemiImplicit", 15), ("SolverXPBD", 13)])
def test_every_setting_is_bound_with_its_default_and_doc(solver, least):
    settings_type = getattr(novaphy.solvers, solver + "Settings")
    fields = settings_type.fields()
    assert len(fields) == len({f["name"] for f in fields}) >= least
    for field in fields:
        assert getattr(settings_type(), field["name"]) == field["default"], field["name"]
        assert field["doc"] and getattr(settings_type, field["name"]).__doc__ == field["doc"], field["name"]
