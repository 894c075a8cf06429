"""Mesh files: every format with its scale and units, missing and unreadable ones, and no leaks."""

import os
import subprocess
import sys

from file_opens import FileOpens, write_canary_files, write_hostile_meshes
import mujoco
import numpy as np
import pytest
from repository import model_path, TEST_MODELS
from service_tutorial.sim.urdf import builder
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot

MESHES = os.path.join(TEST_MODELS, 'meshes')
HALF_BOX = np.array([0.05, 0.03, 0.02])  # every box mesh file is 0.1 x 0.06 x 0.04 m
INERTIAL = ('<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" '
            'ixz="0" iyz="0"/></inertial>')


def mesh_robot(*meshes, tag='visual'):
    """Return a one-link robot with a <tag> for each (filename, scale or None)."""
    shapes = ''.join(
        f'<{tag}><geometry><mesh filename="{filename}"'
        f'{f" scale={chr(34)}{scale}{chr(34)}" if scale else ""}/></geometry></{tag}>'
        for filename, scale in meshes)
    return f'<robot name="meshy"><link name="base">{INERTIAL}{shapes}</link></robot>'


def link_bounds(world, model_name, link, group):
    """Return (low, high) corners of a link's mesh geoms of a group, in the link's frame."""
    mj_model, data = world.model, world.data
    body = mj_model.body(world.models[model_name].scoped(link)).id
    points = []
    for geom in range(mj_model.ngeom):
        if (mj_model.geom_bodyid[geom] != body or mj_model.geom_group[geom] != group
                or mj_model.geom_type[geom] != mujoco.mjtGeom.mjGEOM_MESH):
            continue
        mesh = mj_model.geom_dataid[geom]
        start = mj_model.mesh_vertadr[mesh]
        vertices = mj_model.mesh_vert[start:start + mj_model.mesh_vertnum[mesh]]
        # MuJoCo moves a mesh to its own frame; the geom's pose puts it back where it was.
        in_world = data.geom_xpos[geom] + vertices @ data.geom_xmat[geom].reshape(3, 3).T
        points.append((in_world - data.xpos[body]) @ data.xmat[body].reshape(3, 3))
    assert points, f'no mesh geom of group {group} on {link}'
    points = np.concatenate(points)
    return points.min(axis=0), points.max(axis=0)


def test_every_format_of_meshbot_has_its_size_scale_and_unit():
    world = World()
    model = spawn_file(world, 'meshbot', model_path('meshbot', TEST_MODELS))
    assert model.description.missing_meshes == () and model.description.notes == ()
    expected = [
        ('base_link', builder.VISUAL_GROUP, HALF_BOX),  # ASCII STL
        ('base_link', builder.COLLISION_GROUP, HALF_BOX),  # binary STL
        # Collada in centimetres, turned a quarter about z by its <visual> origin.
        ('dae_link', builder.VISUAL_GROUP, HALF_BOX[[1, 0, 2]]),
        ('obj_link', builder.VISUAL_GROUP, HALF_BOX * [2.0, 1.0, 0.5]),  # OBJ, scale 2 1 0.5
        ('obj_link', builder.COLLISION_GROUP, HALF_BOX * [2.0, 1.0, 0.5]),
    ]
    for link, group, half in expected:
        low, high = link_bounds(world, 'meshbot', link, group)
        np.testing.assert_allclose(low, -half, atol=1e-6, err_msg=link)
        np.testing.assert_allclose(high, half, atol=1e-6, err_msg=link)
    # It stands on its binary STL box.
    world.step(500)
    assert world.get_model_state('meshbot').position[2] == pytest.approx(0.0, abs=1e-4)


@pytest.mark.parametrize('filename, unit', [
    ('box_binary.stl', 1.0), ('box_ascii.stl', 1.0), ('box.obj', 1.0),
    ('box_centimetres.dae', 0.01)])
@pytest.mark.parametrize('tag, group', [('visual', builder.VISUAL_GROUP),
                                        ('collision', builder.COLLISION_GROUP)])
def test_each_format_loads_with_its_scale(filename, unit, tag, group):
    world = World()
    spawn_robot(world, 'meshy', mesh_robot((f'meshes/{filename}', '1.5 2 -0.5'), tag=tag),
                base_dir=TEST_MODELS)
    low, high = link_bounds(world, 'meshy', 'base', group)
    half = HALF_BOX * [1.5, 2.0, 0.5] * (unit / 0.01 if filename.endswith('.dae') else 1.0)
    np.testing.assert_allclose(low, -half, atol=1e-6)
    np.testing.assert_allclose(high, half, atol=1e-6)


@pytest.mark.parametrize('unit, half', [
    ('<unit name="millimeter" meter="0.001"/>', HALF_BOX / 10.0),
    ('', HALF_BOX * 100.0)])
def test_a_collada_unit_is_applied_and_metres_are_the_default(tmp_path, unit, half):
    with open(os.path.join(MESHES, 'box_centimetres.dae')) as dae_file:
        text = dae_file.read()
    (tmp_path / 'box.dae').write_text(
        text.replace('<unit name="centimeter" meter="0.01"/>', unit))
    world = World()
    spawn_robot(world, 'meshy', mesh_robot(('box.dae', None)), base_dir=str(tmp_path))
    low, high = link_bounds(world, 'meshy', 'base', builder.VISUAL_GROUP)
    np.testing.assert_allclose(high - low, 2.0 * half, rtol=1e-6)


def ascii_box():
    with open(os.path.join(MESHES, 'box_ascii.stl'), 'rb') as stl_file:
        return stl_file.read()


BOX_OBJ = ('v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\n'
           'f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n')


@pytest.mark.parametrize('filename, contents, reason', [
    ('empty.stl', b'', 'the file is empty'),
    ('garbage.stl', b'\x01garbage' * 20, 'not a readable STL file (no triangles in it)'),
    ('solid.stl', b'solid x\nendsolid x\n', 'not a readable STL file (no triangles in it)'),
    ('blank.obj', b'  \n\n', 'the file is empty'),
    ('words.obj', b'hello world\n', 'not a readable OBJ file (no triangles in it)'),
    ('huge.stl', ascii_box().replace(b'vertex -0.05 -0.03 -0.02', b'vertex 1e39 -0.03 -0.02', 1),
     'its vertices hold NaN or infinity'),
    ('line.obj', b'v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n', 'its triangles have no area'),
    ('broken.dae', b'<COLLADA><asset>', 'the Collada file does not parse as XML'),
    ('doctype.dae', b'<!DOCTYPE COLLADA [<!ENTITY e "x">]><COLLADA/>',
     'the Collada file contains a DOCTYPE or ENTITY declaration, which is refused'),
    ('unit.dae', b'<COLLADA><asset><unit meter="0"/></asset></COLLADA>',
     "its <unit meter='0'> is not a positive number"),
    ('empty.dae', b'<COLLADA/>', 'not a readable DAE file'),
    ('folder.stl', None, 'no such file'),
])
def test_an_unreadable_mesh_is_left_out_and_the_rest_is_built(tmp_path, filename, contents,
                                                              reason):
    if contents is None:
        (tmp_path / filename).mkdir()
    else:
        (tmp_path / filename).write_bytes(contents)
    (tmp_path / 'good.obj').write_text(BOX_OBJ)
    urdf = mesh_robot((filename, None), ('good.obj', None))
    description = load_urdf(urdf, base_dir=str(tmp_path))
    assert description.missing_meshes == (filename,)
    (note,) = description.notes
    assert note.startswith(f"mesh '{filename}' cannot be had, so it is left out: {reason}")
    model = description.spec.compile()
    assert model.ngeom == 1 and model.nmesh == 1


def test_missing_meshes_are_named_once_in_order_and_the_robot_is_built(caplog):
    world = World()
    with caplog.at_level('WARNING', logger='service_tutorial.world'):
        model = spawn_file(world, 'missingbot', model_path('missingbot', TEST_MODELS))
        world.step(100)
    assert model.description.missing_meshes == ('meshes/not_there.stl',
                                                'package://no_such_package/meshes/arm.dae')
    assert [record.getMessage() for record in caplog.records] == [
        "model 'missingbot': mesh 'meshes/not_there.stl' cannot be had, so it is left out: "
        'no such file',
        "model 'missingbot': mesh 'package://no_such_package/meshes/arm.dae' cannot be had, so "
        'it is left out: no package resolver is available to find its package']
    # What was there is built: the base's box and the marker's mesh.
    mj_model = world.model
    kept = sorted((mj_model.body(mj_model.geom_bodyid[geom]).name, int(mj_model.geom_type[geom]))
                  for geom in range(mj_model.ngeom) if mj_model.geom_bodyid[geom] > 0)
    assert kept == [('missingbot::base_link', mujoco.mjtGeom.mjGEOM_BOX),
                    ('missingbot::marker', mujoco.mjtGeom.mjGEOM_MESH)]
    assert world.get_model_state('missingbot').position[2] == pytest.approx(0.0, abs=1e-3)


def test_a_flat_collision_mesh_is_left_out_and_a_flat_visual_is_kept(tmp_path):
    (tmp_path / 'sheet.obj').write_text('v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n')
    urdf = mesh_robot(('sheet.obj', None)).replace(
        '</link>', '<collision><geometry><mesh filename="sheet.obj"/></geometry></collision>'
                   '</link>')
    description = load_urdf(urdf, base_dir=str(tmp_path))
    assert description.missing_meshes == ()
    assert description.notes == ("link 'base' collision mesh 'sheet.obj' is flat, and MuJoCo "
                                 'collides only with solid shapes: that collision is left out',)
    model = description.spec.compile()
    assert model.ngeom == 1 and model.geom_group[0] == builder.VISUAL_GROUP


def test_the_loaders_read_the_mesh_file_and_nothing_it_points_at(tmp_path):
    canary = write_canary_files(tmp_path)
    share = tmp_path / 'share' / 'hostile_meshes'
    paths = write_hostile_meshes(share, canary)
    resolver = {'hostile_meshes': str(share)}.__getitem__
    urdf = mesh_robot(*((f'package://hostile_meshes/{path}', None) for path in paths))
    with FileOpens(list(canary.values()), str(tmp_path)) as opens:
        description = load_urdf(urdf, package_resolver=resolver)
        description.spec.compile()
    assert opens.opened() == []
    # The world read the mesh files themselves, once each, and nothing else below the share.
    read = sorted(path for path in opens.python_opens if path.startswith(str(share)))
    assert read == sorted(str(share / path) for path in paths)
    assert description.missing_meshes == ('package://hostile_meshes/meshes/entity.dae',)
    # A read through the links is seen.
    with FileOpens(list(canary.values()), str(tmp_path)) as opens:
        with open(share / 'meshes' / 'texture.png') as link:
            link.read()
    assert opens.opened() == [canary['text']]


def test_pycollada_is_imported_only_for_a_collada_mesh():
    # trimesh itself comes with yourdfpy, which imports it; its Collada reader is deferred.
    stl_robot = mesh_robot(('meshes/box_binary.stl', None))
    program = (
        'import sys\n'
        'from service_tutorial.sim.world import World\n'
        'from service_tutorial.testing.spawns import spawn_file, spawn_robot\n'
        'world = World()\n'
        f'spawn_file(world, "diffbot", {model_path("diffbot_ros2", TEST_MODELS)!r})\n'
        f'spawn_robot(world, "stl", {stl_robot!r}, base_dir={TEST_MODELS!r})\n'
        'assert "collada" not in sys.modules\n'
        f'spawn_file(world, "meshbot", {model_path("meshbot", TEST_MODELS)!r})\n'
        'assert "collada" in sys.modules\n')
    result = subprocess.run([sys.executable, '-c', program], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
