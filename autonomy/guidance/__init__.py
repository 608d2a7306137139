"""Guidance: lawnmower survey planning, LOS path following, waypoints and the mission state machine."""
