"""The world node's web page (parameter web): the world and its sensors, live, and a panel."""
