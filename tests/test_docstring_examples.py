"""The Examples sections of every module run as written."""

import doctest
import importlib
import pkgutil

import pytest

import curvdetail

MODULES = sorted(m.name for m in pkgutil.walk_packages(curvdetail.__path__, "curvdetail.")
                 if not m.name.endswith("__main__"))
#: the modules whose docstrings hold examples
WITH_EXAMPLES = [name for name in MODULES
                 if any(t.examples for t in doctest.DocTestFinder().find(importlib.import_module(name)))]


@pytest.mark.parametrize("name", WITH_EXAMPLES)
def test_examples_run_as_written(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
