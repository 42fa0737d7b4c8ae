"""docs/inverse-rendering.md's numbers come from the demos' records: each generated section equals
what its script writes from the committed results.json (examples/two_mirrors.py and
examples/inverse_rendering.py, `--page-from`). A hand-edited number, or a record committed without
regenerating the page, fails here.

Run by ctest with the bindings' suite (QSIL_SOURCE_DIR=<repository>); needs NumPy and SciPy only.
"""
import importlib.util
import json
import os

import pytest

import qsil_shape

ROOT = os.environ.get("QSIL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
PAGE = os.path.join(ROOT, "docs", "inverse-rendering.md")


def load_script(name):
    spec = importlib.util.spec_from_file_location(name, os.path.join(ROOT, "examples", name + ".py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("script", ["two_mirrors", "inverse_rendering"])
def test_the_generated_section_is_the_records(script):
    module = load_script(script)
    with open(os.path.join(ROOT, "docs", module.RECORD)) as f:
        expected = module.page_text(json.load(f))
    with open(PAGE) as f:
        page = f.read()
    begin = qsil_shape.GENERATED_BEGIN % (module.RECORD, module.SCRIPT)
    assert page.count(begin) == 1, "%s: no generated section for %s" % (PAGE, module.RECORD)
    section = page[page.index(begin) + len(begin):]
    section = section[:section.index(qsil_shape.GENERATED_END)]
    assert section.strip("\n") == expected.strip("\n")
