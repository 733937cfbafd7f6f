"""Where the reproduction and benchmark scripts find the public meshes: $CURVDETAIL_MESHES, else
../shared/meshes beside the repository (see ../shared/meshes/README.md for their sources)."""

import os
import sys

from curvdetail.cli import whole_number_from_one as at_least_one  # noqa: F401 (--repeat)

MESHES = os.environ.get("CURVDETAIL_MESHES",
                        os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "meshes"))


def require(*names):
    """Exit with status 1 and a message unless :data:`MESHES` holds every file (or folder) in
    ``names``: before any output folder is made or any work is done."""
    missing = [name for name in names if not os.path.exists(os.path.join(MESHES, name))]
    if missing:
        sys.exit(f"{os.path.basename(sys.argv[0])}: {MESHES!r} does not hold {', '.join(missing)}; set "
                 "CURVDETAIL_MESHES to the folder of the public meshes (../shared/meshes beside the "
                 "repository).")
