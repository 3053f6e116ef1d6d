"""The settings table drives the binding and the reference page: every setting is bound with its doc,
and the committed docs/settings.md is the one tools/make_settings_doc.py makes from the module."""

import contextlib
import io
import os
import sys

import novaphy

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tools"))

import make_settings_doc  # noqa: E402


def test_settings_page_is_up_to_date():
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        make_settings_doc.main()
    with open(os.path.join(ROOT, "docs", "settings.md")) as f:
        committed = f.read()
    assert out.getvalue() == committed, "run: PYTHONPATH=build/python python3 tools/make_settings_doc.py > docs/settings.md"


def test_every_setting_is_bound_with_its_default_and_doc():
    fields = novaphy.solvers.SolverFeatherstoneSettings.fields()
    settings = novaphy.solvers.SolverFeatherstoneSettings()
    assert len(fields) == len({f["name"] for f in fields}) >= 22
    for field in fields:
        assert getattr(settings, field["name"]) == field["default"], field["name"]
        assert field["doc"], field["name"]
        prop = getattr(novaphy.solvers.SolverFeatherstoneSettings, field["name"])
        assert prop.__doc__ == field["doc"], field["name"]
