"""The documentation site builds with no warning (mkdocs --strict: broken links, pages left out
of the nav, docstrings griffe cannot parse as numpydoc). Needs the docs extra, part of the test
extra."""

import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.mark.slow
def test_site_builds_strict(tmp_path):
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                         cwd=ROOT, capture_output=True, text=True, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert run.returncode == 0, run.stderr
    for page in ["index.html", "api/curvdetail/index.html", "tutorials/reconstruct/index.html", "results/index.html"]:
        assert (tmp_path / "site" / page).is_file()
    # one rendered reference entry per public name of each package
    import importlib
    pages = {"curvdetail": "curvdetail", "curvdetail.remesh": "remesh", "curvdetail.filters": "filters",
             "curvdetail.io": "io", "curvdetail.evaluate": "evaluate"}
    missing = []
    for module, page in pages.items():
        html = (tmp_path / "site" / "api" / page / "index.html").read_text(encoding="utf-8")
        missing += [f"{module}.{name}" for name in importlib.import_module(module).__all__
                    if f'id="{module}.{name}"' not in html]
    assert missing == []
