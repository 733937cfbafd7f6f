"""``python -m curvdetail`` runs the command line."""

import subprocess
import sys

import pytest

from curvdetail import __version__


@pytest.mark.slow
def test_python_m_curvdetail_runs_the_command():
    result = subprocess.run([sys.executable, "-m", "curvdetail", "--version"], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0
    assert result.stdout.strip() == f"curvdetail {__version__}"
