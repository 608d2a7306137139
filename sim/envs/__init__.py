"""Gymnasium environments on top of the simulator: ``auvsim/Survey-v1`` and ``auvsim/Waypoint-v1``.

Importing this package registers both ids; the env classes are imported lazily so that
registration stays cheap.
"""

from sim.envs.registration import SURVEY_ID, WAYPOINT_ID, register_envs

register_envs()

__all__ = ["SURVEY_ID", "WAYPOINT_ID", "register_envs"]
