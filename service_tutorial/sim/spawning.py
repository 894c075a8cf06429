"""
Spawn orders: a robot to spawn, checked and built into a Model before anything is attached.

An order's robot is a text in one of the description formats (description_formats.py), as a
RobotSource of robot_files.py gives it; every format goes the same way from here on.

A world spawns a batch of orders with one recompile; each order is checked on its own first, so
that a refused order changes nothing and leaves the others to spawn. This is where an order is
judged, once: its name, its pose and frame, its description; each refusal has its Reason.
"""

from dataclasses import dataclass

from service_tutorial.sim import frames
from service_tutorial.sim import validation
from service_tutorial.sim.description_formats import FORMATS
from service_tutorial.sim.model import Model
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import Reason
from service_tutorial.sim.validation import WorldError


@dataclass(frozen=True)
class SpawnOrder:
    """One robot to spawn: its name, its description, its pose in a frame, its mesh folder."""

    name: str
    text: object  # the robot's description, str or bytes, in model_format
    position: tuple = (0.0, 0.0, 0.0)
    orientation: tuple = frames.IDENTITY_QUATERNION  # (w, x, y, z)
    reference_frame: str = ''  # '' or 'world', a model, 'model::link', or a model of the batch
    base_dir: str = None  # where relative mesh paths resolve
    model_format: str = 'urdf'  # a name of description_formats.FORMATS

    @classmethod
    def of(cls, name, source, **placement):
        """Return the order of a RobotSource (robot_files.py) under name, placed as given."""
        return cls(name, source.text, base_dir=source.base_dir,
                   model_format=source.model_format, **placement)


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
                         f'{", ".join(FORMATS)}', Reason.UNSUPPORTED_FORMAT)
    validation.check_model_name(order.name)
    if order.name in taken or order.name in batch:
        raise WorldError(f'a model named {quoted(order.name)} already exists',
                         Reason.NAME_TAKEN)
    try:
        position = validation.position(order.position)
        orientation = validation.unit_quaternion(order.orientation)
    except WorldError as error:
        raise WorldError(str(error), Reason.BAD_POSE) from None
    earlier = batch.get(order.reference_frame)
    if earlier is not None:  # not in the world yet: where it is about to stand
        frame_position, frame_orientation = earlier.spawn_position, earlier.spawn_orientation
    else:
        frame = frame_state(order.reference_frame)
        frame_position, frame_orientation = frame.position, frame.orientation
    world_position, world_orientation = frames.compose(
        frame_position, frame_orientation, position, orientation)
    description = descriptions.load(order.text, order.base_dir, order.model_format)
    return Model(order.name, description, world_position, world_orientation)


def log_spawned(logger, models):
    """Log where models were spawned (one line for a batch) and each note on their building."""
    places = [f"'{model.name}' at {[round(value, 4) for value in model.spawn_position.tolist()]}"
              for model in models]
    if len(places) == 1:
        logger.info('spawned model %s', places[0])
    elif places:  # a line each would cost a /rosout message each
        logger.info('spawned %d models: %s', len(places), ', '.join(places))
    for model in models:
        for note in model.description.notes:
            logger.warning("model '%s': %s", model.name, note)
