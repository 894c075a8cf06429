"""The world node's web page (parameter web): the world in 3D, live, and the lesson's buttons."""
