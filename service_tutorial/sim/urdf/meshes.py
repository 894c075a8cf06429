"""
Mesh files of a URDF: where they may be read from, and loading them into a robot's MjSpec.

A mesh is only read from below the model's own folder or a package share, so a URDF cannot
make the world read any other file; a path that leads elsewhere is refused. Every format (STL,
binary or ASCII; Collada; OBJ) is read into memory here and decoded by trimesh from those
bytes, so no decoder opens a file of its own (a Collada texture, an OBJ material library),
and MuJoCo gets plain vertices and faces. A mesh that cannot be had (unknown package, missing
or unreadable file, relative path without a base directory) is left out, as Gazebo does.
"""

import functools
import io
import os
import warnings

import mujoco
import numpy as np
from service_tutorial.sim.description import MAX_SIZE
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.urdf.hardened_xml import parse_xml
from service_tutorial.sim.validation import quoted

# File extension -> the trimesh file type that decodes it.
MESH_FORMATS = {'.stl': 'stl', '.dae': 'dae', '.obj': 'obj'}
MESH_EXTENSIONS = tuple(MESH_FORMATS)
MAX_MESH_BYTES = 64 * 1024 * 1024


class MeshMissing(Exception):
    """A mesh that cannot be had; str() says why. The link is built without that geometry."""


class MeshLoader:
    """Adds the mesh files a robot's links name to its spec, each checked by the path rules."""

    def __init__(self, spec, base_dir, package_resolver):
        """Load into spec; relative paths resolve below base_dir, package:// by the resolver."""
        self._spec = spec
        self._given_base_dir = base_dir
        self._package_resolver = package_resolver
        self._decoded = {}  # real path -> (vertices, faces), so a file is read once
        self.files = []  # the real path of every mesh added, one per geometry
        self.missing = []  # (filename as written, why it cannot be had), one per geometry
        self.left_out = []  # notes on the meshes that were had but could not be used

    @functools.cached_property
    def _base_dir(self):
        """Return the real path of the base directory; looked up at the first mesh, if any."""
        return os.path.realpath(self._given_base_dir) if self._given_base_dir else None

    def add(self, mesh, what, *, collision=False):
        """
        Add a yourdfpy <mesh> to the spec and return the MuJoCo mesh's name, or None.

        None means the geometry is left out: the mesh cannot be had (noted in missing), or it
        is a collision mesh whose vertices all lie in one plane, which MuJoCo cannot collide
        with (noted in left_out).
        """
        scale = _checked_scale(mesh.scale, what)
        try:
            path = resolve_mesh_path(mesh.filename, self._base_dir, self._package_resolver)
        except MeshMissing as missing:
            self.missing.append((mesh.filename, str(missing)))
            return None
        return self.add_file(path, mesh.filename, scale, what, collision=collision)

    def add_file(self, path, filename, scale, what, *, collision=False):
        """
        Add the mesh file at a real path its description's own rules allowed; as add() does.

        filename is the name as written, for the notes; scale one number or three (None: 1).
        """
        scale = _checked_scale(scale, what)
        try:
            if path not in self._decoded:
                self._decoded[path] = read_mesh(path)
        except MeshMissing as missing:
            self.missing.append((filename, str(missing)))
            return None
        vertices, faces = self._decoded[path]
        extent = float(np.max(np.ptp(vertices, axis=0).astype(float) * np.abs(scale)))
        if extent > MAX_SIZE:
            raise UrdfError(f'{what} mesh {quoted(filename)} scaled by {scale.tolist()} is '
                            f'{extent:g} m across, more than the limit of {MAX_SIZE:g} m')
        if collision and _is_flat(vertices * scale):
            self.left_out.append(f"{what} collision mesh '{filename}' is flat, and MuJoCo "
                                 'collides only with solid shapes: that collision is left out')
            return None
        mj_mesh = self._spec.add_mesh(name=f'mesh{len(self.files)}')
        mj_mesh.uservert = vertices.ravel()
        mj_mesh.userface = faces.ravel()
        mj_mesh.scale = scale
        # Open surfaces are common in meshes made for looks; bodies carry their URDF inertia.
        mj_mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
        self.files.append(path)
        return mj_mesh.name


def _checked_scale(scale, what):
    """Return a mesh's scale as three numbers, refusing one that is not finite and non-zero."""
    scale = scale if scale is not None else 1.0
    scale = np.broadcast_to(np.asarray(scale, dtype=float), (3,)).copy()
    if not np.all(np.isfinite(scale)) or np.any(scale == 0.0):
        raise UrdfError(f'{what} mesh scale must be finite and non-zero: {scale.tolist()}')
    return scale


def resolve_mesh_path(filename, base_dir, package_resolver):
    """
    Return the real path of a mesh file, refusing anything outside the allowed roots.

    Raise MeshMissing if the file cannot be had, UrdfError if the name is refused. Nothing
    is opened here.
    """
    if not filename:
        raise UrdfError('a <mesh> has no filename')
    allowed_roots = []
    if filename.startswith('package://'):
        package, _, relative = filename[len('package://'):].partition('/')
        if not package or not relative:
            raise UrdfError(f"mesh '{filename}' is not of the form package://<package>/<path>")
        share = _package_share(package, package_resolver)
        candidate = os.path.join(share, relative)
        allowed_roots.append(share)
    elif filename.startswith('file://') or os.path.isabs(filename):
        candidate = filename[len('file://'):] if filename.startswith('file://') else filename
        if not os.path.isabs(candidate):
            raise UrdfError(f"mesh '{filename}' is a file:// URI without an absolute path")
        if base_dir is not None:
            allowed_roots.append(base_dir)
        share = share_holding(candidate, package_resolver)
        if share is not None:
            allowed_roots.append(share)
    elif '://' in filename:
        raise UrdfError(f"mesh '{filename}' uses an unsupported URI scheme")
    else:
        if base_dir is None:
            raise MeshMissing('a relative path, but no base directory is set')
        candidate = os.path.join(base_dir, filename)
        allowed_roots.append(base_dir)
    real_path = os.path.realpath(candidate)
    if not any(_is_within(real_path, root) for root in allowed_roots):
        raise UrdfError(
            f"mesh '{filename}' lies outside the model's folder and package shares")
    if os.path.splitext(real_path)[1].lower() not in MESH_FORMATS:
        raise UrdfError(
            f"mesh '{filename}' has an unsupported format; use one of "
            f"{', '.join(MESH_EXTENSIONS)}")
    if not os.path.isfile(real_path):
        raise MeshMissing('no such file')
    return real_path


def read_mesh(path):
    """Return (vertices, faces) of an allowed mesh file, as decode_mesh() does."""
    try:
        with open(path, 'rb') as mesh_file:
            data = mesh_file.read(MAX_MESH_BYTES + 1)
    except OSError as error:
        raise MeshMissing(f'cannot be read: {error.strerror}') from None
    if len(data) > MAX_MESH_BYTES:
        raise MeshMissing(f'larger than the limit of {MAX_MESH_BYTES} bytes')
    return decode_mesh(data, MESH_FORMATS[os.path.splitext(path)[1].lower()])


def decode_mesh(data, file_type):
    """
    Return (vertices (n, 3) float32, faces (m, 3) int32) of mesh file contents.

    file_type is 'stl', 'dae' or 'obj'. Raise MeshMissing if they hold no usable surface.
    """
    if not data.strip():
        raise MeshMissing('the file is empty')
    meter = collada_meter(data) if file_type == 'dae' else 1.0
    # Imported here: a robot without meshes needs none of it. (yourdfpy imports trimesh
    # anyway; trimesh imports pycollada only for the first Collada file.)
    import trimesh
    try:
        # A file object without a resolver: trimesh reads nothing but these bytes.
        with warnings.catch_warnings(), np.errstate(all='ignore'):
            warnings.simplefilter('ignore')
            loaded = trimesh.load(io.BytesIO(data), file_type=file_type, force='mesh')
            # MuJoCo keeps vertices in single precision.
            vertices = (np.array(loaded.vertices, dtype=float) * meter).astype(np.float32)
        faces = np.array(loaded.faces, dtype=np.int32)
    except Exception as error:
        reason = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise MeshMissing(f'not a readable {file_type.upper()} file ({reason})') from None
    if (vertices.ndim != 2 or len(vertices) < 3 or faces.ndim != 2 or len(faces) == 0
            or faces.min() < 0 or faces.max() >= len(vertices)):
        raise MeshMissing(f'not a readable {file_type.upper()} file (no triangles in it)')
    if not np.all(np.isfinite(vertices)):
        raise MeshMissing('its vertices hold NaN or infinity')
    triangles = vertices[faces].astype(float)
    area = np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0],
                                   triangles[:, 2] - triangles[:, 0]), axis=1).sum() / 2.0
    if not area > 1e-12:
        raise MeshMissing('its triangles have no area')
    return vertices, faces


def collada_meter(data):
    """Return the length of a Collada file's unit in metres (<asset><unit meter>), 1 if none."""
    try:
        root = parse_xml(data, 'the Collada file', huge_tree=True)
    except UrdfError as error:
        raise MeshMissing(str(error)) from None
    for asset in root:
        if isinstance(asset.tag, str) and asset.tag.rpartition('}')[2] == 'asset':
            for unit in asset:
                if isinstance(unit.tag, str) and unit.tag.rpartition('}')[2] == 'unit':
                    text = unit.get('meter', '1')
                    try:
                        meter = float(text)
                    except ValueError:
                        meter = float('nan')
                    if not np.isfinite(meter) or meter <= 0.0:
                        raise MeshMissing(f"its <unit meter='{text}'> is not a positive number")
                    return meter
    return 1.0


def _is_flat(vertices):
    """Return True if the vertices span no volume (all in one plane or line)."""
    centred = vertices - vertices.mean(axis=0)
    singular = np.linalg.svd(centred, compute_uv=False)
    return bool(singular[-1] <= 1e-9 * max(singular[0], 1e-300))


def _package_share(package, package_resolver):
    if package_resolver is None:
        raise MeshMissing('no package resolver is available to find its package')
    try:
        share = package_resolver(package)
    except Exception:
        share = None
    if not share or not os.path.isdir(share):
        raise MeshMissing(f"package '{package}' is not found")
    return os.path.realpath(share)


def share_holding(path, package_resolver):
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
