"""
An SDF world read: its physics, its static models (the scenery) and the others (its entities).

A <world> holds <model>s and <include>s (the two built-in Fuel models among them), posed in the
world frame or relative to the world's <frame>s and models. Its <physics> (the default one,
else the first) gives the timestep, max_step_size, 0.001 s if it says none as SDF has it; its
<gravity> the gravity, 0 0 -9.8 if none; its <spherical_coordinates> where its origin lies on
the Earth (geodesy.py), for the NavSat sensors of its models. Static models become the world's
scenery, built where they stand; every other model is an entity, spawned from its own SDF (the
<model> as written, or an include's model with its name and static) at its pose in the world,
under its name with whitespace made '_' as gz-sim's topics have it. A moving model none of
whose collisions is left once its missing meshes are left out would fall for ever: it is left
out, and named. A world has no ground but the one it says: Fuel's Ground Plane, or a plane of
its own.
"""

import copy
from dataclasses import dataclass

from lxml import etree

from service_tutorial.sim.geodesy import SphericalCoordinates
from service_tutorial.sim.sdf.elements import child_text, is_world_system, name_of, number
from service_tutorial.sim.sdf.elements import numbers
from service_tutorial.sim.sdf.paths import SdfPaths
from service_tutorial.sim.sdf.poses import FrameGraph, read_pose, WORLD_FRAME
from service_tutorial.sim.sdf.reader import parse_sdf, SdfReading
from service_tutorial.sim.validation import check_model_name, DescriptionError, quoted
from service_tutorial.sim.validation import Reason, WorldError

DEFAULT_STEP = 0.001  # s, SDF's max_step_size
DEFAULT_GRAVITY = (0.0, 0.0, -9.8)
MAX_STEP = 0.1  # s, the longest step the world takes (its timestep parameter's bound)
MAX_GRAVITY = 1000.0  # m/s^2 along any axis
MAX_MODELS = 1000  # of one world
# The surface and the axes of <spherical_coordinates> that gz-sim's NavSat computes with.
EARTH_SURFACE = 'EARTH_WGS84'
EAST_NORTH_UP = 'ENU'
TAG = 'sdf'  # every SDF world's tag, in the world's listing


@dataclass(frozen=True)
class SdfEntity:
    """A moving model of a world: its name in the world, its own SDF and its pose."""

    name: str
    text: str
    base_dir: str  # where its relative uris resolve (None: the world came as text)
    position: tuple
    orientation: tuple  # (w, x, y, z)


@dataclass(frozen=True)
class SdfWorld:
    """What an SDF world says, read."""

    name: str
    timestep: float
    gravity: tuple
    static_models: tuple = ()  # (SdfModel, world pose) of each static model
    entities: tuple = ()  # SdfEntity of each moving model
    not_simulated: tuple = ()  # what the world holds and does not simulate, named
    left_out: tuple = ()  # names of the moving models left out: nothing of them collides
    files: tuple = ()  # the files it was read from, includes and model.config
    version: tuple = (1, 11)  # its SDF's
    spherical_coordinates: object = None  # a geodesy.SphericalCoordinates, or None


def world_name(root, what):
    """Return the name of the <world> an SDF root holds, or refuse a root that holds none."""
    worlds = [child for child in root if isinstance(child.tag, str)]
    if [child.tag for child in worlds] != ['world']:
        if any(child.tag == 'model' for child in worlds):
            raise DescriptionError(f'{what} holds a <model>, not a <world>: spawn it as an '
                                   'entity (SpawnEntity)', Reason.UNSUPPORTED_FORMAT)
        raise DescriptionError(f'{what} must hold one <world>, not '
                               f'{", ".join(f"<{child.tag}>" for child in worlds) or "none"}')
    return worlds[0].get('name') or 'default'


def read_sdf_world(text, what, base_dir, package_resolver, read_file):
    """Return the SdfWorld of SDF text; base_dir: its file's folder (None for a text)."""
    root, version = parse_sdf(text, what)
    name = world_name(root, what)
    element = root.find('world')
    shown = f'world {quoted(name)}'
    reading = SdfReading(SdfPaths(package_resolver), read_file)
    reading.notes.children(element, 'world', shown)
    for plugin in element.findall('plugin'):
        if not is_world_system(plugin.get('filename')):
            reading.notes.add(f'<plugin> {quoted(plugin.get("filename") or "")}', shown)
    timestep, gravity = _physics(element, shown)
    spherical = _spherical_coordinates(element.find('spherical_coordinates'), shown,
                                       reading.notes)
    graph = FrameGraph(name, shown, root=WORLD_FRAME)
    models = []
    for child in element:
        if child.tag == 'frame':
            pose, relative_to = read_pose(child.find('pose'), version, f'frame of {shown}')
            graph.add('frame', name_of(child, shown), pose, relative_to,
                      child.get('attached_to', ''))
        elif child.tag in ('model', 'include'):
            placed = _top_model(reading, child, version, base_dir, shown)
            if placed is None:
                continue
            model, pose, relative_to, element_static = placed
            if len(models) >= MAX_MODELS:
                raise DescriptionError(f'{shown} has more than {MAX_MODELS} models',
                                       Reason.UNSUPPORTED_CONTENT)
            graph.add('model', model.name, pose, relative_to)
            graph.nest(model.name, model.graph)
            models.append((model, element_static))
    static_models, entities, left_out, names = [], [], [], set()
    for model, element_static in models:
        pose = graph.pose(model.name, f'model {quoted(model.name)}')
        if model.static:
            static_models.append((model, pose))
            continue
        entity_name = '_'.join(model.name.split())
        try:
            check_model_name(entity_name)
        except WorldError as error:
            raise DescriptionError(f'{shown}: {error}', Reason.NAME_INVALID) from None
        if entity_name in names:
            raise DescriptionError(f'{shown} has two moving models named {quoted(entity_name)}',
                                   Reason.NAME_TAKEN)
        names.add(entity_name)
        if not any(not shape.missing for link in model.links for shape in link.collisions):
            if any(shape.missing for link in model.links for shape in link.collisions):
                left_out.append(model.name)
                continue
        entities.append(SdfEntity(name=entity_name, text=_entity_text(model, entity_name,
                                                                      element_static),
                                  base_dir=model.base_dir, position=tuple(pose[0]),
                                  orientation=tuple(pose[1])))
    return SdfWorld(name=name, timestep=timestep, gravity=gravity,
                    static_models=tuple(static_models), entities=tuple(entities),
                    not_simulated=tuple(reading.notes), left_out=tuple(left_out),
                    files=tuple(dict.fromkeys(reading.files)), version=version,
                    spherical_coordinates=spherical)


def _top_model(reading, element, version, base_dir, shown):
    """Return (SdfModel, pose, relative_to, static as its element says) of a world's model."""
    if element.tag == 'model':
        model = reading.model(element, version, base_dir)
        pose, relative_to = reading.placed(element, model, version,
                                           f'model {quoted(model.name)} of {shown}')
        return model, pose, relative_to, model.static
    included = reading.include(element, version, base_dir, depth=0, scope='', shown=shown)
    if included is None:
        return None
    model, pose, relative_to = included
    return model, pose, relative_to, _static_in(model.element)


def _static_in(element):
    """Return what a <model> element itself says of <static>."""
    return (child_text(element, 'static') or '').lower() in ('true', '1')


def _physics(world, shown):
    """Return (timestep, gravity) of a world: its default <physics>, its <gravity>."""
    physics = world.findall('physics')
    chosen = next((element for element in physics
                   if (element.get('default') or '').strip().lower() in ('true', '1')),
                  physics[0] if physics else None)
    timestep = DEFAULT_STEP
    if chosen is not None:
        timestep = number(chosen, 'max_step_size', DEFAULT_STEP, f'<physics> of {shown}',
                          minimum=1e-6, maximum=MAX_STEP)
    gravity = DEFAULT_GRAVITY
    text = child_text(world, 'gravity')
    if text:
        gravity = tuple(numbers(text, 3, f'<gravity> of {shown}', limit=MAX_GRAVITY))
    return timestep, gravity


def _spherical_coordinates(element, shown, notes):
    """Return the SphericalCoordinates of a world's <spherical_coordinates>, or None."""
    if element is None:
        return None
    what = f'<spherical_coordinates> of {shown}'
    for tag, supported in (('surface_model', EARTH_SURFACE),
                           ('world_frame_orientation', EAST_NORTH_UP)):
        text = child_text(element, tag)
        if text and text != supported:
            notes.add(f'<{tag}> {quoted(text)} (taken as {supported})', what)
    return SphericalCoordinates(
        latitude_deg=number(element, 'latitude_deg', 0.0, what, minimum=-90.0, maximum=90.0),
        longitude_deg=number(element, 'longitude_deg', 0.0, what, minimum=-180.0,
                             maximum=180.0),
        elevation=number(element, 'elevation', 0.0, what, minimum=-1e7, maximum=1e7),
        heading_deg=number(element, 'heading_deg', 0.0, what, minimum=-360.0, maximum=360.0))


def _entity_text(model, name, element_static):
    """Return the SDF an entity spawns from: its model, named, without its top <pose>."""
    element = copy.deepcopy(model.element)
    element.set('name', name)
    element.attrib.pop('placement_frame', None)
    for child in element.findall('pose'):
        element.remove(child)
    if element_static != model.static:  # an include's <static> said otherwise
        for child in element.findall('static'):
            element.remove(child)
        etree.SubElement(element, 'static').text = 'true' if model.static else 'false'
    version = f'{model.version[0]}.{model.version[1]}'
    return f'<sdf version="{version}">{etree.tostring(element, encoding="unicode")}</sdf>'
