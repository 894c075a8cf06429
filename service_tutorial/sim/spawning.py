"""
Spawn orders: a robot to spawn, checked and built into a Model before anything is attached.

An order's robot is URDF or, with format 'mjcf', MJCF; both go the same way from here on.

A world spawns a batch of orders with one recompile; each order is checked on its own first, so
that a refused order changes nothing and leaves the others to spawn.
"""

from dataclasses import dataclass

import numpy as np

from service_tutorial.sim import frames
from service_tutorial.sim import validation
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.model import Model
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES
from service_tutorial.sim.validation import DescriptionError
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import WorldError

FORMATS = ('urdf', 'mjcf')


@dataclass(frozen=True)
class SpawnOrder:
    """One robot to spawn: its name, its URDF or MJCF, its pose in a frame, its mesh folder."""

    name: str
    urdf_xml: object  # the robot's text, str or bytes: URDF, or MJCF by model_format
    position: tuple = (0.0, 0.0, 0.0)
    orientation: tuple = frames.IDENTITY_QUATERNION  # (w, x, y, z)
    reference_frame: str = ''  # '' or 'world', a model, 'model::link', or a model of the batch
    base_dir: str = None  # where mesh paths relative to the URDF resolve
    model_format: str = 'urdf'  # 'urdf' or 'mjcf' (sim/mjcf.py)


def prepared_batch(orders, *, taken, frame_state, descriptions):
    """
    Check orders and build their Models with prepared_model(); nothing is attached yet.

    Return, for each order, its Model or the WorldError that refused it; and the Models by
    name. descriptions: the world's DescriptionCache, which loads a text once for the batch.
    """
    outcomes, batch = [], {}
    loader = descriptions.for_batch()
    for order in orders:
        try:
            batch[order.name] = prepared_model(order, taken=taken, batch=batch,
                                               frame_state=frame_state, descriptions=loader)
            outcomes.append(batch[order.name])
        except WorldError as error:
            outcomes.append(error)
    return outcomes, batch


def prepared_model(order, *, taken, batch, frame_state, descriptions):
    """
    Check an order and build its Model, or raise WorldError; nothing is attached yet.

    taken: the names in the world; batch: the models of the same batch prepared so far, by
    name (an order may stand relative to one of them); frame_state: the world's ModelState of
    a reference frame; descriptions: what loads the robot's description (a DescriptionCache).
    """
    if order.model_format not in FORMATS:
        raise WorldError(f'format {quoted(str(order.model_format))} is none of '
                         f'{", ".join(FORMATS)}')
    validation.check_model_name(order.name)
    if order.name in taken or order.name in batch:
        raise WorldError(f'a model named {quoted(order.name)} already exists')
    position = validation.position(order.position)
    orientation = validation.unit_quaternion(order.orientation)
    earlier = batch.get(order.reference_frame)
    if earlier is not None:  # not in the world yet: where it is about to stand
        frame_position, frame_orientation = earlier.spawn_position, earlier.spawn_orientation
    else:
        frame = frame_state(order.reference_frame)
        frame_position, frame_orientation = frame.position, frame.orientation
    world_position, world_orientation = frames.compose(
        frame_position, frame_orientation, position, orientation)
    try:
        description = descriptions.load(order.urdf_xml, order.base_dir, order.model_format)
    except UrdfError as error:
        raise DescriptionError(str(error)) from None
    return Model(order.name, description, world_position, world_orientation)


def log_spawned(logger, models):
    """Log where models were spawned (one line for a batch) and each note on their building."""
    places = [f"'{model.name}' at {np.round(model.spawn_position, 4).tolist()}"
              for model in models]
    if len(places) == 1:
        logger.info('spawned model %s', places[0])
    elif places:  # a line each would cost a /rosout message each
        logger.info('spawned %d models: %s', len(places), ', '.join(places))
    for model in models:
        for note in model.description.notes:
            logger.warning("model '%s': %s", model.name, note)


def read_urdf_file(path):
    """Return the bytes of a URDF file, at most one more than the size limit, or refuse."""
    try:
        with open(path, 'rb') as urdf_file:
            return urdf_file.read(MAX_MODEL_XML_BYTES + 1)
    except OSError as error:
        raise WorldError(f"cannot read URDF file '{path}': {error.strerror}") from None
