"""
mujoco_world as the lesson runs it: the world node with the lesson's panel on its web page.

The world node (world_node/) imports nothing of the lesson, and the lesson's panel
(lesson/web_panel.py) reaches the world only through ROS; this module puts the two together, as
a launch file composes nodes. The executable mujoco_world runs main(); the tests' harness starts
its worlds with lesson_world().
"""

from service_tutorial.lesson.web_panel import LessonPanel
from service_tutorial.world_node.node import main as world_main
from service_tutorial.world_node.node import MujocoWorld


def lesson_world(**kwargs):
    """Return the world node (MujocoWorld's keyword arguments), with the lesson's panel."""
    return MujocoWorld(web_panel=LessonPanel, **kwargs)


def main(args=None):
    """Run the world with the lesson's panel on its web page (web:=true)."""
    return world_main(args, web_panel=LessonPanel)


if __name__ == '__main__':
    main()
