"""GetSimulatorFeatures: what the world serves of the standard, gathered from its groups."""

from importlib.metadata import version

from simulation_interfaces.msg import SimulatorFeatures
from simulation_interfaces.srv import GetSimulatorFeatures


def gathered_features(groups):
    """Return the SimulatorFeatures that the groups' FEATURES and SPAWN_FORMATS add up to."""
    features = sorted({feature for group in groups for feature in group.FEATURES})
    formats = dict.fromkeys(spawn_format for group in groups
                            for spawn_format in getattr(group, 'SPAWN_FORMATS', ()))
    return SimulatorFeatures(
        features=features, spawn_formats=list(formats),
        custom_info=f'service_tutorial: a MuJoCo {version("mujoco")} world; the lesson\'s '
                    'gazebo_msgs-style services are under /mujoco/')


class FeatureService:
    """Serves get_simulator_features: the union of what each standard service group serves."""

    def __init__(self, node, groups):
        """Answer for groups, objects whose FEATURES (and SPAWN_FORMATS) say what they serve."""
        self.features = gathered_features(groups)
        self.features_srv = node.serve(
            GetSimulatorFeatures, 'get_simulator_features', self.get_simulator_features_callback)

    def get_simulator_features_callback(self, request, response):
        """Say which of the standard's features the world serves."""
        response.features = self.features
        return response
