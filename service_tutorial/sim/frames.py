"""
Reference frames and pose composition, all in one place and all by MuJoCo's own functions.

Quaternions are MuJoCo's (w, x, y, z). A frame is named as gazebo_ros names it: '' or 'world',
a model (its base link), or 'model::link'.
"""

from dataclasses import dataclass

import mujoco
import numpy as np
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import Reason
from service_tutorial.sim.validation import SCOPE_SEPARATOR
from service_tutorial.sim.validation import WORLD_FRAMES
from service_tutorial.sim.validation import WorldError

IDENTITY_QUATERNION = (1.0, 0.0, 0.0, 0.0)
_Z_AXIS = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True, eq=False)
class ModelState:
    """Pose and twist of a body, expressed in a reference frame."""

    position: np.ndarray          # (3,) metres
    orientation: np.ndarray       # (4,) unit quaternion (w, x, y, z), MuJoCo order
    linear_velocity: np.ndarray   # (3,) m/s
    angular_velocity: np.ndarray  # (3,) rad/s


def yaw_quaternion(yaw):
    """Return the (w, x, y, z) quaternion of a turn by yaw radians about z."""
    quaternion = np.zeros(4)
    mujoco.mju_axisAngle2Quat(quaternion, _Z_AXIS, float(yaw))
    return quaternion


def rpy_quaternion(rpy):
    """Return the (w, x, y, z) quaternion of roll, pitch and yaw about fixed axes (URDF, SDF)."""
    quaternion = np.zeros(4)
    mujoco.mju_euler2Quat(quaternion, np.asarray(rpy, float), 'XYZ')
    return quaternion


def principal_inertia(orientation, tensor):
    """
    Return (principal moments, largest first; their axes' (w, x, y, z) quaternion) of an inertia.

    The tensor is given in a frame turned by orientation; the axes are in its parent.
    """
    moments, axes, local = np.zeros(3), np.zeros(9), np.zeros(4)
    mujoco.mju_eig3(moments, axes, local, np.asarray(tensor, float).ravel())
    quaternion = np.zeros(4)
    mujoco.mju_mulQuat(quaternion, np.asarray(orientation, float), local)
    return moments, quaternion


def rotate_tensor(quaternion, tensor):
    """Return a 3x3 tensor (an inertia) given in a frame turned by quaternion, in its parent."""
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, np.asarray(quaternion, float))
    rotation = rotation.reshape(3, 3)
    return rotation @ np.asarray(tensor, float) @ rotation.T


def rotate(quaternion, vector):
    """Return vector turned by quaternion: from a frame's axes into its parent's."""
    result = np.zeros(3)
    mujoco.mju_rotVecQuat(result, np.asarray(vector, float), np.asarray(quaternion, float))
    return result


def rotate_back(quaternion, vector):
    """Return vector turned by the inverse of quaternion: from a parent's axes into a frame's."""
    inverse = np.zeros(4)
    mujoco.mju_negQuat(inverse, np.asarray(quaternion, float))
    return rotate(inverse, vector)


def compose(frame_position, frame_orientation, position, orientation):
    """Return the pose that (position, orientation), given in a frame, has in its parent."""
    result_position, result_orientation = np.zeros(3), np.zeros(4)
    mujoco.mju_mulPose(result_position, result_orientation,
                       np.asarray(frame_position, float), np.asarray(frame_orientation, float),
                       np.asarray(position, float), np.asarray(orientation, float))
    return result_position, result_orientation


def relative(frame_position, frame_orientation, position, orientation):
    """Return the pose that (position, orientation), given in the parent, has in a frame."""
    inverse_position, inverse_orientation = np.zeros(3), np.zeros(4)
    mujoco.mju_negPose(inverse_position, inverse_orientation,
                       np.asarray(frame_position, float), np.asarray(frame_orientation, float))
    return compose(inverse_position, inverse_orientation, position, orientation)


def expressed_in(frame, state):
    """
    Return a world-frame state as seen from frame (another world-frame state).

    The twist is the difference of the two frames' velocities, expressed in the reference
    frame, as gazebo_ros reports it.
    """
    position, orientation = relative(frame.position, frame.orientation, state.position,
                                     state.orientation)
    return ModelState(
        position=position, orientation=orientation,
        linear_velocity=rotate_back(frame.orientation,
                                    state.linear_velocity - frame.linear_velocity),
        angular_velocity=rotate_back(frame.orientation,
                                     state.angular_velocity - frame.angular_velocity))


def in_world(frame, state):
    """Return a state given relative to frame (a world-frame state) in the world frame."""
    position, orientation = compose(frame.position, frame.orientation, state.position,
                                    state.orientation)
    return ModelState(
        position=position, orientation=orientation,
        linear_velocity=frame.linear_velocity + rotate(frame.orientation,
                                                       state.linear_velocity),
        angular_velocity=frame.angular_velocity + rotate(frame.orientation,
                                                         state.angular_velocity))


def body_state(mj_model, data, body_id):
    """Return the world-frame state of a body; the caller keeps the kinematics current."""
    if body_id == 0:  # the world itself, which needs no kinematics
        return ModelState(position=np.zeros(3), orientation=np.array(IDENTITY_QUATERNION),
                          linear_velocity=np.zeros(3), angular_velocity=np.zeros(3))
    twist = np.zeros(6)
    mujoco.mj_objectVelocity(mj_model, data, mujoco.mjtObj.mjOBJ_BODY, body_id, twist, 0)
    return ModelState(position=data.xpos[body_id].copy(),
                      orientation=data.xquat[body_id].copy(),
                      linear_velocity=twist[3:], angular_velocity=twist[:3])


def body_accelerations(mj_model, data, body_ids):
    """
    Return (linear, angular) acceleration of each body in the world frame, as of the state.

    MuJoCo's accelerations carry gravity as an upward acceleration of the world (what an
    accelerometer reads); it is taken out, so a body at rest has none.
    """
    if not body_ids:
        return []
    mujoco.mj_rnePostConstraint(mj_model, data)  # once for every body asked about
    accelerations = []
    for body_id in body_ids:
        acceleration = np.zeros(6)
        mujoco.mj_objectAcceleration(mj_model, data, mujoco.mjtObj.mjOBJ_BODY, body_id,
                                     acceleration, 0)
        accelerations.append((acceleration[3:] + mj_model.opt.gravity, acceleration[:3]))
    return accelerations


def frame_body(reference_frame, models, mj_model):
    """Return the id of the body a reference frame names, given the spawned models by name."""
    if not isinstance(reference_frame, str):
        raise WorldError(f'unknown reference frame {reference_frame!r}', Reason.UNKNOWN_FRAME)
    if reference_frame in WORLD_FRAMES:
        return 0
    if reference_frame in models:
        return models[reference_frame].root_id
    model_name, separator, link = reference_frame.partition(SCOPE_SEPARATOR)
    if separator and model_name in models and link:
        body_id = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_BODY, reference_frame)
        if body_id > 0:
            return body_id
    raise WorldError(f'unknown reference frame {quoted(reference_frame)}',
                     Reason.UNKNOWN_FRAME)
