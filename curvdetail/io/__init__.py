"""Files: meshes (`mesh`; PLY through plyfile, `ply`) and the one atomic writer every
output goes through (`atomic`)."""

from .atomic import atomic_write, check_output_path
from .mesh import MeshFileError, read_mesh, write_mesh

__all__ = ["MeshFileError", "atomic_write", "check_output_path", "read_mesh", "write_mesh"]
