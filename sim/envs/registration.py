"""Register the auvsim environments with gymnasium (idempotent).

``import sim.envs`` registers them; from a fresh process (e.g. an ``AsyncVectorEnv``
worker) ``gymnasium.make("sim.envs:auvsim/Survey-v1")`` imports this package first.

Retired versions stay registered so that making one says why it was retired and what
replaces it, instead of silently running changed behaviour under the old id.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry
from gymnasium.error import DeprecatedEnv

SURVEY_ID = "auvsim/Survey-v1"
WAYPOINT_ID = "auvsim/Waypoint-v1"

# Time limits live in the envs' options (truncation), so no TimeLimit wrapper is added.
_ENVS = {
    SURVEY_ID: "sim.envs.survey_env:SurveyEnv",
    WAYPOINT_ID: "sim.envs.waypoint_env:WaypointEnv",
}

RETIRED = {
    "auvsim/Survey-v0": f"auvsim/Survey-v0 is retired: its sonar episodes ended on the first step (the start already "
                        f"saw every target of the scenario's small area). Use {SURVEY_ID}: an area larger than the "
                        "sonar's reach, targets placed per episode from the seed, the start out of their view.",
    "auvsim/Waypoint-v0": f"auvsim/Waypoint-v0 is retired: its per-episode current never acted on the hull. Use "
                          f"{WAYPOINT_ID}, where the hull drifts with the episode's current.",
}


def retired_env(*, env_id: str, **_kwargs) -> None:
    """Entry point of a retired id. Raises ``gymnasium.error.DeprecatedEnv`` saying why."""
    raise DeprecatedEnv(RETIRED[env_id])


# batched forms (``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``)
_VECTOR_ENVS = {SURVEY_ID: "sim.envs.survey_vector:make_survey_vector_env"}


def register_envs() -> None:
    for env_id, entry_point in _ENVS.items():
        if env_id not in registry:
            register(id=env_id, entry_point=entry_point, vector_entry_point=_VECTOR_ENVS.get(env_id),
                     disable_env_checker=False)
    for env_id in RETIRED:
        if env_id not in registry:
            register(id=env_id, entry_point="sim.envs.registration:retired_env", kwargs={"env_id": env_id},
                     disable_env_checker=True)
