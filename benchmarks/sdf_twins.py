"""
SDF twins of the package's URDF robots and of the yard, for the benchmark's SDF rows.

A twin is the same robot written in SDF 1.8 as sdformat's own URDF import writes it: each
link posed relative_to the joint it hangs from, each joint posed relative_to its parent link
with the URDF origin, the axis in the joint frame; the same inertials, shapes and colours. The
yard twin is a Gazebo world: Fuel's Ground Plane and Sun, the yard's walls as a static model
and tinybot (without its plugin blocks, which SDF names in <plugin>s gz-sim reads) by model://,
from model folders written into a folder of the caller's.
"""

import os

from lxml import etree

# The Gazebo world the yard's twin is, its models found by model://.
YARD_WORLD = """<sdf version="1.8">
  <world name="yard_sdf">
    <physics name="2ms" type="ignored"><max_step_size>0.002</max_step_size></physics>
    <gravity>0 0 -9.81</gravity>
    <plugin filename="gz-sim-physics-system" name="gz::sim::systems::Physics"/>
    <plugin filename="gz-sim-user-commands-system" name="gz::sim::systems::UserCommands"/>
    <plugin filename="gz-sim-scene-broadcaster-system"
            name="gz::sim::systems::SceneBroadcaster"/>
    <include><uri>https://fuel.gazebosim.org/1.0/OpenRobotics/models/Ground Plane</uri></include>
    <include><uri>https://fuel.gazebosim.org/1.0/OpenRobotics/models/Sun</uri></include>
    <include><uri>model://yard</uri></include>
    <include><uri>model://tinybot</uri></include>
  </world>
</sdf>
"""
MODEL_CONFIG = ('<?xml version="1.0"?>\n<model><name>{name}</name><version>1.0</version>'
                '<sdf version="1.8">model.sdf</sdf></model>\n')


def _pose(origin, relative_to=''):
    """Return the SDF <pose> of a URDF <origin> (None: the identity)."""
    xyz = origin.get('xyz', '0 0 0') if origin is not None else '0 0 0'
    rpy = origin.get('rpy', '0 0 0') if origin is not None else '0 0 0'
    frame = f' relative_to="{relative_to}"' if relative_to else ''
    return f'<pose{frame}>{xyz} {rpy}</pose>'


def _geometry(geometry):
    """Return the SDF <geometry> of a URDF one."""
    shape = next(child for child in geometry if isinstance(child.tag, str))
    if shape.tag == 'box':
        inner = f'<box><size>{shape.get("size")}</size></box>'
    elif shape.tag == 'cylinder':
        inner = (f'<cylinder><radius>{shape.get("radius")}</radius><length>'
                 f'{shape.get("length")}</length></cylinder>')
    elif shape.tag == 'sphere':
        inner = f'<sphere><radius>{shape.get("radius")}</radius></sphere>'
    else:
        scale = shape.get('scale', '1 1 1')
        scale = scale if len(scale.split()) == 3 else ' '.join([scale] * 3)
        inner = f'<mesh><uri>{shape.get("filename")}</uri><scale>{scale}</scale></mesh>'
    return f'<geometry>{inner}</geometry>'


def sdf_twin(urdf, *, name=None, static=False):
    """Return the SDF 1.8 twin of URDF text (its <gazebo> blocks left out); static: scenery."""
    robot = etree.fromstring(urdf.encode())
    colours = {material.get('name'): material.find('color').get('rgba')
               for material in robot.findall('material') if material.find('color') is not None}
    parent_joint = {joint.find('child').get('link'): joint for joint in robot.findall('joint')}
    parts = [f'<sdf version="1.8"><model name="{name or robot.get("name")}">'
             + ('<static>true</static>' if static else '')]
    for link in robot.findall('link'):
        link_name = link.get('name')
        if link_name == 'world':
            continue
        joint = parent_joint.get(link_name)
        pose = f'<pose relative_to="{joint.get("name")}"/>' if joint is not None and \
            joint.find('parent').get('link') != 'world' else ''
        parts.append(f'<link name="{link_name}">{pose}')
        inertial = link.find('inertial')
        if inertial is not None:
            inertia = inertial.find('inertia')
            moments = ''.join(f'<{key}>{inertia.get(key, "0")}</{key}>'
                              for key in ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz'))
            parts.append(f'<inertial>{_pose(inertial.find("origin"))}<mass>'
                         f'{inertial.find("mass").get("value")}</mass><inertia>{moments}'
                         '</inertia></inertial>')
        for kind in ('collision', 'visual'):
            for index, element in enumerate(link.findall(kind)):
                material = ''
                if kind == 'visual' and element.find('material') is not None:
                    named = element.find('material')
                    colour = named.find('color').get('rgba') if named.find('color') is not None \
                        else colours.get(named.get('name'))
                    material = f'<material><diffuse>{colour}</diffuse></material>' \
                        if colour else ''
                parts.append(f'<{kind} name="{kind}_{index}">{_pose(element.find("origin"))}'
                             f'{_geometry(element.find("geometry"))}{material}</{kind}>')
        parts.append('</link>')
    for joint in robot.findall('joint'):
        parent, kind = joint.find('parent').get('link'), joint.get('type')
        parts.append(f'<joint name="{joint.get("name")}" type="{kind}"><parent>{parent}</parent>'
                     f'<child>{joint.find("child").get("link")}</child>'
                     f'{_pose(joint.find("origin"), parent if parent != "world" else "")}')
        if kind != 'fixed':
            axis = joint.find('axis')
            limit = joint.find('limit')
            limits = (f'<limit><lower>{limit.get("lower")}</lower><upper>{limit.get("upper")}'
                      '</upper></limit>') if kind in ('revolute', 'prismatic') else ''
            parts.append(f'<axis><xyz>{axis.get("xyz") if axis is not None else "1 0 0"}'
                         f'</xyz>{limits}</axis>')
        parts.append('</joint>')
    parts.append('</model></sdf>')
    return ''.join(parts)


def write_model_folder(folder, name, sdf):
    """Write a model folder (model.config and model.sdf) for an SDF model; return its path."""
    model_folder = os.path.join(folder, name)
    os.makedirs(model_folder, exist_ok=True)
    with open(os.path.join(model_folder, 'model.config'), 'w') as config:
        config.write(MODEL_CONFIG.format(name=name))
    with open(os.path.join(model_folder, 'model.sdf'), 'w') as model:
        model.write(sdf)
    return model_folder
