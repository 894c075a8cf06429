"""
Turn MJCF text into a description the world spawns as it spawns a URDF robot's.

An entity's MJCF is MuJoCo's own: bodies, joints, geoms and sites, its default classes, meshes
and materials, its actuators, sensors and contact excludes. Its worldbody holds exactly one
body, the entity's tree. As MuJoCo means it, a <freejoint/> on that body lets the entity move
and fall, a body without joints is welded to the world (a static object), and a hinge or slide
there hinges it to the world. The body's own pos and orientation place it relative to the
spawn pose; the entity's pose is that body's. MuJoCo's attach brings it into the world under
the prefix '<entity>::', as a URDF robot's elements are; elements without a name get one
('body1', 'joint2', 'actuator1'), so that joint states and frames can name them.

Refused, each naming the value: <include> and every file other than a mesh file within the
root the text came from (the share of its package, or its own folder when it is in none),
with '..' or links resolved first; text given as a string names no file at all (AssetError);
a mesh file that is not there (AssetError, missing). Mesh files are read and decoded here as
a URDF's are (meshes.read_mesh), so MuJoCo opens no file itself; texture files are refused,
builtin textures and colours are not. Refused as well (DescriptionError): a worldbody with no
body, with more than one, or with elements of its own; a top body in a <frame> or a mocap
body; what the world would leave behind when the entity goes, or what acts beyond it
(tendons, equality constraints, keyframes, contact pairs, flexes, skins, heightfields, engine
plugins, custom data, a skybox); <replicate>; builtin textures over MAX_TEXTURE_SIDE pixels
a side; shapes larger than MAX_SIZE; MJCF that MuJoCo does not compile.

The world's physics stays the world's: <option>, <size>, <visual> and <statistic> are ignored,
each with a note, rather than changing the timestep or gravity for every model.
"""

import os
import types

from lxml import etree
import mujoco
from service_tutorial.sim import plugins
from service_tutorial.sim.description import MAX_SIZE
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins.joint_state_publisher import JOINT_STATE_PUBLISHER
from service_tutorial.sim.plugins.joint_state_publisher import JointStateConfig
from service_tutorial.sim.urdf.builder import RobotDescription
from service_tutorial.sim.urdf.gazebo import PluginBlock
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES
from service_tutorial.sim.urdf.hardened_xml import parse_xml
from service_tutorial.sim.urdf.meshes import MESH_EXTENSIONS
from service_tutorial.sim.urdf.meshes import MeshMissing
from service_tutorial.sim.urdf.meshes import read_mesh
from service_tutorial.sim.urdf.meshes import share_holding
from service_tutorial.sim.validation import AssetError
from service_tutorial.sim.validation import DescriptionError
from service_tutorial.sim.validation import quoted

# Sections of <mujoco> an entity may have, and those ignored because they set the world's.
SECTIONS = ('compiler', 'asset', 'default', 'worldbody', 'actuator', 'sensor', 'contact')
WORLD_SECTIONS = ('option', 'size', 'visual', 'statistic')
# Of <asset> and <contact>, the children an entity may have.
ASSETS = ('mesh', 'material', 'texture')
CONTACTS = ('exclude',)
# Elements refused wherever they stand: they bring what the world could not take away again,
# or (replicate) multiply a few lines into as many bodies as they like.
REFUSED_ANYWHERE = ('plugin', 'flexcomp', 'composite', 'attach', 'skin', 'flex', 'replicate')
# The largest side of a builtin texture, in pixels: MuJoCo makes every pixel at compile time.
MAX_TEXTURE_SIDE = 1024
# Folder attributes of <compiler> that a mesh file is found by, in MuJoCo's order.
MESH_FOLDERS = ('meshdir', 'assetdir')
_HINGE_AND_SLIDE = (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)
_WORLD_SHAPES = (int(mujoco.mjtGeom.mjGEOM_PLANE), int(mujoco.mjtGeom.mjGEOM_HFIELD))
# The plugin block an MJCF model's joint state publisher stands for, as a URDF would write it.
JOINT_STATES_BLOCK = PluginBlock(filename='libgazebo_ros_joint_state_publisher.so',
                                 name='joint_state_publisher',
                                 parameters=types.MappingProxyType({}))


def load_mjcf(model_xml, *, base_dir=None, package_resolver=None):
    """
    Build a RobotDescription from MJCF text, or raise DescriptionError naming the problem.

    base_dir: the folder of the file the text came from (None: a string, which may name no
    file); its mesh files must lie in the share of the package holding it (package_resolver
    maps a package name to its share), or below base_dir if no package holds it.
    """
    root = _parse(model_xml)
    notes = _checked_sections(root)
    meshes = _read_meshes(root, base_dir, package_resolver)
    try:
        spec = mujoco.MjSpec.from_string(etree.tostring(root, encoding='unicode'))
    except Exception as error:
        raise DescriptionError(f'MJCF is not valid: {_one_line(error)}') from None
    top = _top_body(spec)
    for mesh in spec.meshes:
        if mesh.name in meshes:
            vertices, faces = meshes[mesh.name][1]
            mesh.uservert = vertices.ravel()
            mesh.userface = faces.ravel()
    _name_elements(spec)
    try:
        compiled = spec.compile()
    except Exception as error:
        raise DescriptionError(f'MJCF does not compile: {_one_line(error)}') from None
    _check_sizes(compiled)
    if compiled.body_mocapid[1] >= 0:
        raise DescriptionError(f'MJCF top body {quoted(top.name)} is a mocap body, which an '
                               'entity may not be')
    # The top body goes to the spawn pose; its own pose is applied by the world (Model).
    root_position = tuple(float(value) for value in compiled.body_pos[1])
    root_orientation = tuple(float(value) for value in compiled.body_quat[1])
    top.pos = [0.0, 0.0, 0.0]
    top.quat = [1.0, 0.0, 0.0, 0.0]
    top.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
    joint_types = [mujoco.mjtJoint(int(kind)) for kind in compiled.jnt_type]
    joints = tuple(compiled.joint(index).name for index, kind in enumerate(joint_types)
                   if kind in _HINGE_AND_SLIDE)
    notes += [f'joint {quoted(compiled.joint(index).name)} is a ball joint, which '
              'joint_states does not carry' for index, kind in enumerate(joint_types)
              if kind == mujoco.mjtJoint.mjJNT_BALL]
    free = any(kind == mujoco.mjtJoint.mjJNT_FREE for kind in joint_types)
    setups = ()
    if joints:
        setups = (plugins.PluginSetup(JOINT_STATE_PUBLISHER, JOINT_STATES_BLOCK,
                                      JointStateConfig(joint_names=joints)),)
    return RobotDescription(
        robot_name=root.get('model') or '', spec=spec, root_link=top.name, anchored=not free,
        root_position=root_position, root_orientation=root_orientation,
        links=tuple(compiled.body(index).name for index in range(1, compiled.nbody)),
        joints=joints,
        actuators=tuple(compiled.actuator(index).name for index in range(compiled.nu)),
        plugins=setups, mesh_files=tuple(path for path, _ in meshes.values()),
        notes=tuple(notes))


def _parse(model_xml):
    """Parse MJCF text with the hardened parser and return its <mujoco> element."""
    data = model_xml.encode('utf-8') if isinstance(model_xml, str) else bytes(model_xml)
    if len(data) > MAX_MODEL_XML_BYTES:
        raise DescriptionError(f'MJCF is {len(data)} bytes, more than the limit of '
                               f'{MAX_MODEL_XML_BYTES}')
    if not data.strip():
        raise DescriptionError('MJCF is empty')
    if b'\x00' in data:
        raise DescriptionError('MJCF must be UTF-8 text')
    try:
        root = parse_xml(data, 'MJCF')
    except UrdfError as error:
        raise DescriptionError(str(error)) from None
    tag = root.tag if isinstance(root.tag, str) else ''
    if tag != 'mujoco':
        raise DescriptionError(f'MJCF must have the root element <mujoco>, not <{tag[:40]}>')
    return root


def _checked_sections(root):
    """Refuse the elements an entity may not have; drop the world's; return the notes."""
    notes = []
    for element in root.iter('include'):
        raise AssetError(f'MJCF has an <include file={quoted(element.get("file") or "")}>; '
                         "an entity's MJCF must be one file")
    for element in root.iter(*REFUSED_ANYWHERE):
        raise DescriptionError(f'MJCF element <{element.tag}> is not supported in a spawned '
                               'entity')
    for section in list(root):
        if not isinstance(section.tag, str):
            continue
        if section.tag in WORLD_SECTIONS:
            notes.append(f'MJCF <{section.tag}> is ignored: it would change the whole '
                         "world's, which stays as the world was started")
            root.remove(section)
        elif section.tag not in SECTIONS:
            raise DescriptionError(f'MJCF section <{section.tag}> is not supported in a '
                                   'spawned entity (it would outlive or reach beyond it)')
        allowed = {'asset': ASSETS, 'contact': CONTACTS}.get(section.tag)
        for child in section if allowed is not None else ():
            if isinstance(child.tag, str) and child.tag not in allowed:
                raise DescriptionError(f'MJCF <{section.tag}><{child.tag}> is not supported '
                                       f'in a spawned entity; <{section.tag}> may hold '
                                       f'{", ".join(f"<{tag}>" for tag in allowed)}')
    for texture in root.iter('texture'):
        if texture.get('type') == 'skybox':
            raise DescriptionError(f'MJCF texture {quoted(texture.get("name") or "")} is a '
                                   "skybox, which would change the whole world's sky")
        for side in ('width', 'height'):
            text = texture.get(side, '0').strip()
            if not text.isdigit() or int(text) > MAX_TEXTURE_SIDE:
                raise DescriptionError(f'MJCF texture {quoted(texture.get("name") or "")} '
                                       f'{side} must be a whole number of pixels up to '
                                       f'{MAX_TEXTURE_SIDE}: {quoted(text)}')
        for attribute in texture.attrib:
            if attribute.startswith('file'):
                raise AssetError(f'MJCF texture file {quoted(texture.get(attribute))} is not '
                                 'read: an entity may have builtin textures only')
    return notes


def _read_meshes(root, base_dir, package_resolver):
    """
    Read each mesh file the MJCF names, by the path rules; return name -> (path, mesh).

    The <mesh> loses its file attribute and gets the name MuJoCo would have given it (the
    file's name without extension); the vertices and faces go into the spec after parsing.
    """
    folders = {}
    for compiler in root.iter('compiler'):
        for attribute in MESH_FOLDERS:
            if compiler.get(attribute) is not None:
                folders[attribute] = compiler.attrib.pop(attribute)
        for attribute in ('texturedir',):
            compiler.attrib.pop(attribute, None)  # texture files are refused anyway
    folder = folders.get('meshdir', folders.get('assetdir', ''))
    meshes = {}
    for mesh in root.iter('mesh'):
        filename = mesh.attrib.pop('file', None)
        if filename is None:
            continue
        path = _mesh_path(filename, folder, base_dir, package_resolver)
        try:
            decoded = read_mesh(path)
        except MeshMissing as reason:  # it is there (_mesh_path), but of no use
            raise AssetError(f'MJCF mesh file {quoted(filename)} cannot be used: {reason}') \
                from None
        name = mesh.get('name') or os.path.splitext(os.path.basename(filename))[0]
        mesh.set('name', name)
        meshes[name] = (path, decoded)
    return meshes


def _mesh_path(filename, folder, base_dir, package_resolver):
    """Return the real path of a mesh file, or refuse one outside the text's root."""
    shown = quoted(filename)
    if base_dir is None:
        raise AssetError(f'MJCF names mesh file {shown}, but MJCF given as a string may name '
                         'no file; spawn it by its uri, or give the mesh as vertices')
    if '://' in filename or '\0' in filename:
        raise AssetError(f'MJCF mesh file {shown} is not a plain path')
    base_dir = os.path.realpath(base_dir)
    root = share_holding(base_dir, package_resolver) or base_dir
    path = os.path.realpath(os.path.join(base_dir, folder, filename))
    if not path.startswith(root.rstrip(os.sep) + os.sep):
        raise AssetError(f'MJCF mesh file {shown} lies outside {quoted(root)}, the folder '
                         'its MJCF may read files from')
    if not os.path.isfile(path):
        raise AssetError(f'MJCF mesh file {shown} is not there ({quoted(path)})', missing=True)
    if os.path.splitext(path)[1].lower() not in MESH_EXTENSIONS:
        raise AssetError(f'MJCF mesh file {shown} has a format the world does not read; use '
                         f'one of {", ".join(MESH_EXTENSIONS)}')
    return path


def _top_body(spec):
    """Return the one body of the worldbody, refusing anything else directly in it."""
    world = spec.worldbody
    bodies = list(world.bodies)
    if not bodies:
        raise DescriptionError('MJCF worldbody holds no body; an entity is one tree of '
                               'bodies with one body at its top')
    if len(bodies) > 1:
        names = ', '.join(quoted(body.name or '(unnamed)') for body in bodies[:5])
        raise DescriptionError(f'MJCF worldbody holds {len(bodies)} top-level bodies '
                               f'({names}); an entity is one tree: put them under one body')
    for kind, elements in (('geom', world.geoms), ('site', world.sites),
                           ('joint', world.joints), ('camera', world.cameras),
                           ('light', world.lights), ('frame', world.frames)):
        if list(elements):
            raise DescriptionError(f'MJCF worldbody holds a <{kind}> of its own; everything '
                                   'of an entity belongs inside its top body')
    return bodies[0]


def _name_elements(spec):
    """Give every unnamed body, joint and actuator a name of its own kind and number."""
    for kind, elements in (('body', spec.bodies[1:]), ('joint', spec.joints),
                           ('actuator', spec.actuators)):
        taken = {element.name for element in elements}
        number = 0
        for element in elements:
            if element.name:
                continue
            while True:
                number += 1
                if f'{kind}{number}' not in taken:
                    break
            element.name = f'{kind}{number}'
            taken.add(element.name)


def _check_sizes(compiled):
    """Refuse a geom larger than MAX_SIZE across; planes are infinite and refused."""
    for geom in range(compiled.ngeom):
        if int(compiled.geom_type[geom]) in _WORLD_SHAPES:
            raise DescriptionError('MJCF has a plane, which only the world may have')
        extent = 2.0 * float(compiled.geom_rbound[geom])
        if extent > MAX_SIZE:
            name = compiled.geom(geom).name or f'#{geom}'
            raise DescriptionError(f'MJCF geom {quoted(name)} is {extent:g} m across, more than '
                                   f'the limit of {MAX_SIZE:g} m')


def _one_line(error):
    """Return a MuJoCo error as one line without its 'Error: ' prefix."""
    return ' '.join(str(error).split()).removeprefix('Error: ')
