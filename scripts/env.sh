# Source this file to use the built workspace: `source scripts/env.sh` (bash or zsh).
# It activates the project's virtual environment and the colcon install space that
# scripts/setup made, so `ros2 run`-style executables, rclpy and srv_interfaces are found:
# .venv and install/ on the PyPI wheels, .venv-jazzy and install-jazzy/ in a shell where
# ROS 2 Jazzy is sourced.
_service_tutorial_root=$(cd "$(dirname "${BASH_SOURCE[0]:-${(%):-%x}}")/.." && pwd)
if [ -n "${ROS_DISTRO:-}" ]; then
  _service_tutorial_suffix=-jazzy
else
  _service_tutorial_suffix=
fi
if [ ! -f "$_service_tutorial_root/install$_service_tutorial_suffix/setup.bash" ]; then
  echo "service_tutorial is not built yet: run $_service_tutorial_root/scripts/setup" >&2
else
  # shellcheck disable=SC1091
  . "$_service_tutorial_root/.venv$_service_tutorial_suffix/bin/activate"
  if [ -z "${ROS_DISTRO:-}" ]; then
    # ROS 2 from the PyPI wheels: the virtual environment is the underlay.
    export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
    export CMAKE_PREFIX_PATH="$VIRTUAL_ENV${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
  fi
  # shellcheck disable=SC1091
  . "$_service_tutorial_root/install$_service_tutorial_suffix/local_setup.bash"
  export PATH="$_service_tutorial_root/install$_service_tutorial_suffix/service_tutorial/lib/service_tutorial:$PATH"
fi
unset _service_tutorial_root _service_tutorial_suffix
