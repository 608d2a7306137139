"""Register the auvsim environments with gymnasium (idempotent).

``import sim.envs`` registers them; from a fresh process (e.g. an ``AsyncVectorEnv``
worker) ``gymnasium.make("sim.envs:auvsim/Survey-v0")`` imports this package first.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

SURVEY_ID = "auvsim/Survey-v0"
WAYPOINT_ID = "auvsim/Waypoint-v0"

# Time limits live in the envs' options (truncation), so no TimeLimit wrapper is added.
_ENVS = {
    SURVEY_ID: "sim.envs.survey_env:SurveyEnv",
    WAYPOINT_ID: "sim.envs.waypoint_env:WaypointEnv",
}


def register_envs() -> None:
    for env_id, entry_point in _ENVS.items():
        if env_id not in registry:
            register(id=env_id, entry_point=entry_point, disable_env_checker=False)
