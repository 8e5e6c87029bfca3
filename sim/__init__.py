"""Physics of the team: quadrotors, ropes, payload, ground, sensors."""
