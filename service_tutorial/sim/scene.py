"""The world every model is spawned into: physics options, ground, sky, sun and scenery."""

import dataclasses
import functools

import mujoco
from service_tutorial.sim.urdf.builder import CONTACT_TIME_CONSTANT

EARTH_GRAVITY = (0.0, 0.0, -9.81)  # m/s^2, a world's unless its file says otherwise

# The ground's grid and the sky, as MuJoCo's builtin textures draw them. Every compile, spawns
# and deletes too, copies their pixels into the new model, and what follows in the same call
# runs the slower for the bytes that went through the caches: they are kept small. A grid of
# 128 texels draws its lines as 256 do, a shade wider close up; a smooth gradient of 32
# texels a face renders within 2 levels of 255 of one of 256.
_TEXTURES = (
    {'name': 'ground_grid', 'type': mujoco.mjtTexture.mjTEXTURE_2D,
     'builtin': mujoco.mjtBuiltin.mjBUILTIN_CHECKER, 'mark': mujoco.mjtMark.mjMARK_EDGE,
     'rgb1': [0.25, 0.27, 0.3], 'rgb2': [0.32, 0.34, 0.37], 'markrgb': [0.6, 0.6, 0.6],
     'width': 128, 'height': 128},
    {'name': 'sky', 'type': mujoco.mjtTexture.mjTEXTURE_SKYBOX,
     'builtin': mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, 'rgb1': [0.55, 0.68, 0.82],
     'rgb2': [0.1, 0.12, 0.15], 'width': 32, 'height': 192},
)


@functools.cache
def _texture_pixels():
    """
    Return (width, height, channels, pixels) of each texture, drawn by MuJoCo once.

    Drawing them took most of the time of every compile of a world, spawns and deletes too;
    the pixels drawn once are the same every time.
    """
    spec = mujoco.MjSpec()
    for texture in _TEXTURES:
        spec.add_texture(**texture)
    model = spec.compile()
    pixels = []
    for index in range(model.ntex):
        width, height = int(model.tex_width[index]), int(model.tex_height[index])
        channels, start = int(model.tex_nchannel[index]), int(model.tex_adr[index])
        pixels.append((width, height, channels,
                       model.tex_data[start:start + width * height * channels].tobytes()))
    return tuple(pixels)


def _add_textures(spec):
    """Add the ground's and the sky's textures, and the ground's material."""
    for texture, (width, height, channels, pixels) in zip(_TEXTURES, _texture_pixels()):
        added = spec.add_texture(name=texture['name'], type=texture['type'], width=width,
                                 height=height, nchannel=channels)
        added.data = pixels
    material = spec.add_material(name='ground_grid', texrepeat=[1.0, 1.0],
                                 texuniform=True, reflectance=0.1)
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = 'ground_grid'


@dataclasses.dataclass(frozen=True)
class Scene:
    """What every spec a world builds starts from: its physics options and its scenery."""

    timestep: float
    gravity: tuple
    scenery: object = None  # a scenery.Scenery, or None for the bare plane

    def spec(self):
        """Return a new spec of the world without models."""
        return make_scene(self.timestep, self.gravity, self.scenery)


def make_scene(timestep, gravity, scenery=None):
    """
    Return the spec of a world without models: physics options, ground, sky, sun, scenery.

    A scenery with a ground of its own (an SDF world's) takes the place of the plane.
    """
    spec = mujoco.MjSpec()
    spec.modelname = 'service_tutorial'
    # Attaching copies the robot: its description stays as loaded, and deleting the robot
    # from the spec later frees all of it.
    spec.copy_during_attach = True
    # MuJoCo compiles textures and meshes on a pool of threads it makes for every compile:
    # starting them costs more (0.3 ms) than the work they share, spawns and deletes included.
    spec.compiler.usethread = False
    spec.compiler.degree = False
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    option = spec.option
    option.timestep = timestep
    option.gravity = gravity
    # Velocity servos on light wheels need the implicit damping term to stay stable.
    option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    option.impratio = 10.0
    # MuJoCo's automatic reset would reset every robot; the world resets only the robot that
    # went unstable, see recovery.py.
    option.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET
    _add_textures(spec)
    if scenery is None or not scenery.own_ground:
        # A plane collides everywhere; its size only sets how far the floor is drawn.
        spec.worldbody.add_geom(
            name='ground_plane', type=mujoco.mjtGeom.mjGEOM_PLANE, size=[25.0, 25.0, 0.05],
            material='ground_grid', friction=[1.0, 0.005, 0.0001],
            solref=[CONTACT_TIME_CONSTANT, 1.0])
    spec.worldbody.add_light(
        name='sun', type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0.0, 0.0, 10.0],
        dir=[0.3, 0.2, -1.0], diffuse=[0.7, 0.7, 0.7], specular=[0.2, 0.2, 0.2],
        castshadow=False)
    if scenery is not None:
        scenery.attach(spec)
    return spec
