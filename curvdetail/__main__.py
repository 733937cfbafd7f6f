"""``python -m curvdetail``: the ``curvdetail`` command (for environments without the script)."""

import sys

from .cli import main

sys.exit(main())
