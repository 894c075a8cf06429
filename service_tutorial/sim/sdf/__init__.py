"""
SDF, Gazebo's format, read as gz-sim (Gazebo Harmonic, ROS 2 Jazzy's Gazebo) reads it.

paths.py finds what a uri names, elements.py reads values and names what is not simulated,
poses.py resolves poses and frames, links.py and reader.py read models into their links and
joints posed in the model frame, builder.py makes a MuJoCo spec of a model, and world.py reads
a world: its physics, its static models (scenery) and the others (entities).
"""
