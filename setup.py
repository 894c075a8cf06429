from glob import glob

from setuptools import find_packages, setup

package_name = 'service_tutorial'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/models', glob('models/*.urdf') + glob('models/*.xml')),
        ('share/' + package_name + '/worlds', glob('worlds/*.xml')),
        ('share/' + package_name + '/config', glob('config/*.yaml') + glob('config/*.rviz')),
        ('share/' + package_name + '/launch', glob('launch/*.launch.py')),
    ],
    install_requires=['setuptools', 'mujoco', 'yourdfpy', 'numpy', 'pillow', 'xacro', 'viser'],
    zip_safe=True,
    maintainer='service_tutorial maintainers',
    maintainer_email='maintainers@service-tutorial.dev',
    description='ROS 2 port of the ROS 1 services lesson, with MuJoCo in place of Gazebo.',
    license='Apache-2.0',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'mujoco_world = service_tutorial.lesson_world:main',
            'robot_turning_server = service_tutorial.lesson.robot_turning_server:main',
            'robot_turning_client = service_tutorial.lesson.robot_turning_client:main',
            ('robot_turning_action_server = '
             'service_tutorial.lesson.robot_turning_action_server:main'),
            ('robot_turning_action_client = '
             'service_tutorial.lesson.robot_turning_action_client:main'),
            'spawn_model_client = service_tutorial.lesson.spawn_model_client:main',
            'delete_model_client = service_tutorial.lesson.delete_model_client:main',
            'reset_simulation_client = service_tutorial.lesson.reset_simulation_client:main',
            'turning_demo = service_tutorial.pictures.turning_demo:main',
            'save_snapshot = service_tutorial.pictures.save_snapshot:main',
            'sensor_pictures = service_tutorial.pictures.sensor_pictures:main',
            'create = service_tutorial.ros_gz.create:main',
            'parameter_bridge = service_tutorial.ros_gz.parameter_bridge:main',
            'image_bridge = service_tutorial.ros_gz.image_bridge:main',
        ],
    },
)
