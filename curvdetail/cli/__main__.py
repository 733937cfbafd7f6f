"""``python -m curvdetail.cli``: the ``curvdetail`` command."""

import sys

from . import main

sys.exit(main())
