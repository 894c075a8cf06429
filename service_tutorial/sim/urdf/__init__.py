"""URDF to MuJoCo: hardened XML, mesh path rules, <gazebo> blocks and the spec builder."""
