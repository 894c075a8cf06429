"""
Mesh files of a URDF: where they may be read from, and loading them into a robot's MjSpec.

A mesh is only read from below the model's own folder or a package share, so a URDF cannot
make the world read any other file.
"""

import os

import numpy as np
from service_tutorial.sim.urdf.hardened_xml import UrdfError

MESH_EXTENSIONS = ('.stl', '.obj')


class MeshLoader:
    """Adds the mesh files a robot's links name to its spec, each checked by the path rules."""

    def __init__(self, spec, base_dir, package_resolver):
        """Load into spec; relative paths resolve below base_dir, package:// by the resolver."""
        self._spec = spec
        self._base_dir = os.path.realpath(base_dir) if base_dir else None
        self._package_resolver = package_resolver
        self.files = []

    def add(self, mesh, what):
        """Add a yourdfpy <mesh> to the spec and return the name of the MuJoCo mesh."""
        path = resolve_mesh_path(mesh.filename, self._base_dir, self._package_resolver)
        scale = mesh.scale if mesh.scale is not None else 1.0
        scale = np.broadcast_to(np.asarray(scale, dtype=float), (3,)).copy()
        if not np.all(np.isfinite(scale)) or np.any(scale == 0.0):
            raise UrdfError(f'{what} mesh scale must be finite and non-zero')
        mj_mesh = self._spec.add_mesh(name=f'mesh{len(self.files)}', file=path)
        mj_mesh.scale = scale
        self.files.append(path)
        return mj_mesh.name


def resolve_mesh_path(filename, base_dir, package_resolver):
    """Return the real path of a mesh file, refusing anything outside the allowed roots."""
    if not filename:
        raise UrdfError('a <mesh> has no filename')
    allowed_roots = []
    if filename.startswith('package://'):
        package, _, relative = filename[len('package://'):].partition('/')
        if not package or not relative:
            raise UrdfError(f"mesh '{filename}' is not of the form package://<package>/<path>")
        share = _package_share(package, filename, package_resolver)
        candidate = os.path.join(share, relative)
        allowed_roots.append(share)
    elif filename.startswith('file://') or os.path.isabs(filename):
        candidate = filename[len('file://'):] if filename.startswith('file://') else filename
        if not os.path.isabs(candidate):
            raise UrdfError(f"mesh '{filename}' is a file:// URI without an absolute path")
        if base_dir is not None:
            allowed_roots.append(base_dir)
        share = _share_holding(candidate, package_resolver)
        if share is not None:
            allowed_roots.append(share)
    elif '://' in filename:
        raise UrdfError(f"mesh '{filename}' uses an unsupported URI scheme")
    else:
        if base_dir is None:
            raise UrdfError(f"mesh '{filename}' is a relative path but no base directory is set")
        candidate = os.path.join(base_dir, filename)
        allowed_roots.append(base_dir)
    real_path = os.path.realpath(candidate)
    if not any(_is_within(real_path, root) for root in allowed_roots):
        raise UrdfError(
            f"mesh '{filename}' lies outside the model's folder and package shares")
    extension = os.path.splitext(real_path)[1].lower()
    if extension == '.dae':
        raise UrdfError(
            f"mesh '{filename}' is COLLADA (.dae), which MuJoCo does not read; "
            'convert it to .stl or .obj')
    if extension not in MESH_EXTENSIONS:
        raise UrdfError(
            f"mesh '{filename}' has an unsupported format; use one of "
            f"{', '.join(MESH_EXTENSIONS)}")
    if not os.path.isfile(real_path):
        raise UrdfError(f"mesh '{filename}' does not exist")
    return real_path


def _package_share(package, filename, package_resolver):
    if package_resolver is None:
        raise UrdfError(f"mesh '{filename}' needs a package resolver, and none is available")
    try:
        share = package_resolver(package)
    except Exception:
        share = None
    if not share or not os.path.isdir(share):
        raise UrdfError(f"mesh '{filename}' names package '{package}', which is not found")
    return os.path.realpath(share)


def _share_holding(path, package_resolver):
    """Return the share directory of the package whose files hold path, if there is one."""
    if package_resolver is None:
        return None
    parts = os.path.normpath(path).split(os.sep)
    for index in range(len(parts) - 1):
        if parts[index] != 'share':
            continue
        try:
            share = package_resolver(parts[index + 1])
        except Exception:
            continue
        if share and os.path.realpath(share) == os.path.realpath(
                os.sep.join(parts[:index + 2])):
            return os.path.realpath(share)
    return None


def _is_within(path, root):
    root = os.path.realpath(root)
    return path == root or path.startswith(root.rstrip(os.sep) + os.sep)
