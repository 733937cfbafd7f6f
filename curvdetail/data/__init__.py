"""Example meshes shipped with the package.

``terrainA_1k.obj``: a 1,089-vertex disk-topology terrain patch (SRTM 1-arc-second elevation
data of the Sierra Nevada, tile N36W119, x/y/z in km; public domain, NASA/USGS), lightly smoothed.
"""

import os

_HERE = os.path.dirname(os.path.abspath(__file__))


def example_path(name="terrainA_1k.obj"):
    """Absolute path of a bundled example mesh."""
    path = os.path.join(_HERE, name)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no bundled example named {name!r}; available: "
                                f"{', '.join(sorted(f for f in os.listdir(_HERE) if not f.endswith('.py')))}")
    return path
