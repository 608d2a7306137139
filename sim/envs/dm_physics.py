"""The auvsim simulation as a ``dm_control.mujoco.Physics`` ([dmcontrol2020]).

:class:`AuvPhysics` is the physics of the dm_control environments in :mod:`sim.envs.dm`.
It wraps, in dm_control's own wrappers (``dm_control.mujoco.wrapper.MjData`` around an
existing ``mujoco.MjData``), the very ``mujoco.MjModel`` / ``mujoco.MjData`` that the
auvsim simulation advances (:class:`sim.scene.physics.Physics`): ``physics.data.ptr`` *is*
the simulation's ``data``, not a copy, so ``physics.data.qpos``, ``physics.named.data.qpos``
and every other dm_control readout see the simulation as it is.

Time: one dm_control step is one decision interval. ``timestep()`` is the task's
``decision_interval_s``, and ``step(n)`` advances ``n`` decision intervals by calling the
shared task's ``advance`` (:meth:`sim.envs.waypoint_task.WaypointTask.advance`,
:meth:`sim.envs.survey_task.SurveyTask.advance`): the auvsim loop with the thrusters, the
Fossen hydrodynamic wrench, the current and, for the Survey task, the whole mission
(sensors, navigation filter, with sonar the FLS and perception), at the scenario's physics
and autonomy rates. A raw ``mj_step`` would skip the hydrodynamic and thruster forces,
so this physics never calls one by itself. ``time()`` is the task's decision clock
(decisions x interval, s); MuJoCo's own clock is ``physics.data.time``.
"""

from __future__ import annotations

import warnings
from typing import Protocol

import numpy as np

from sim.dynamics.truth import VehicleTruth
from sim.scene.physics import Physics

with warnings.catch_warnings():
    # dm_control probes its OpenGL backends on import; GLFW warns when there is no display.
    # Nothing here renders.
    warnings.filterwarnings("ignore", module="glfw")
    from dm_control import mujoco as dm_mujoco
    from dm_control.mujoco import wrapper as dm_wrapper

__all__ = ["AuvPhysics", "SimulationTask"]


class SimulationTask(Protocol):
    """What :class:`AuvPhysics` needs of a shared task (``WaypointTask``, ``SurveyTask``)."""

    @property
    def sim_physics(self) -> Physics: ...

    @property
    def decision_interval_s(self) -> float: ...

    @property
    def t_s(self) -> float: ...

    def advance(self) -> None: ...


class AuvPhysics(dm_mujoco.Physics):
    """A ``dm_control.mujoco.Physics`` over the simulation a shared task advances.

    Args:
        task: the shared task (:class:`sim.envs.waypoint_task.WaypointTask` or
            :class:`sim.envs.survey_task.SurveyTask`); its ``sim_physics`` is wrapped.

    The Survey task builds a new mission, hence a new ``MjModel`` / ``MjData``, every
    episode: :meth:`bind` (run by :meth:`after_reset`, which ``control.Environment.reset``
    calls after the task's ``initialize_episode``) wraps the new one, as dm_control's
    ``reload_from_*`` methods do; ``physics.model`` / ``physics.data`` / ``physics.named``
    then refer to the episode's.

    Named readouts of the AUV's true state (from :meth:`sim.scene.physics.Physics.truth`,
    the state the Waypoint observation is built from): :meth:`pos_ned` (3,) m,
    :meth:`rpy_rad` (3,) rad, :meth:`nu_body` (6,), :meth:`velocity_body_mps` (3,),
    :meth:`rates_body_radps` (3,), :meth:`depth_m`, :meth:`altitude_m`, :meth:`time_s`,
    :meth:`vehicle_truth`. Reading them does not change the trajectory.

    MuJoCo warnings raised during :meth:`step` raise ``dm_control.rl.control.PhysicsError``
    as in dm_control (``physics.suppress_physics_errors()`` logs them instead).

    Not supported: ``copy``, pickling (the simulation's state lives beyond MjData:
    thruster rotors, current, navigation filter, mission) and ``reset`` to a keyframe.
    """

    def __init__(self, task: SimulationTask) -> None:
        self._task = task
        self._sim = task.sim_physics
        super().__init__(dm_wrapper.MjData(self._sim.data))

    # ------------------------------------------------------------------ binding
    @property
    def sim(self) -> Physics:
        """The auvsim simulation wrapped now (``sim.model`` is ``self.model.ptr``,
        ``sim.data`` is ``self.data.ptr``)."""
        return self._sim

    def bind(self) -> None:
        """Wrap the task's simulation if it is not the one wrapped now (the Survey task's
        per-episode mission); a no-op otherwise."""
        sim = self._task.sim_physics
        if sim is not self._sim or self.data.ptr is not sim.data:
            self._sim = sim
            self._reload_from_data(dm_wrapper.MjData(sim.data))

    # ------------------------------------------------------------------ dm_control's Physics API
    def step(self, n_sub_steps: int = 1) -> None:
        """Advance ``n_sub_steps`` decision intervals (the task's ``advance``: thrusters, Fossen
        wrench, MuJoCo at the physics rate; Survey: the whole mission loop), holding the
        action of the task's latest ``begin_step``.

        Raises:
            dm_control.rl.control.PhysicsError: MuJoCo raised a warning meanwhile.
        """
        with self.check_invalid_state():
            for _ in range(int(n_sub_steps)):
                self._task.advance()

    def timestep(self) -> float:
        """One dm_control step: the task's decision interval, s (the MuJoCo step is
        ``self.model.opt.timestep``)."""
        return float(self._task.decision_interval_s)

    def time(self) -> float:
        """Time since the episode's start, s: the task's decision clock."""
        return float(self._task.t_s)

    def reset(self, keyframe_id: int | None = None) -> None:
        """A no-op: the episode's state (start pose, current, layout, mission) is drawn from
        the task's generator and set by the dm_control task's ``initialize_episode``, which
        ``control.Environment.reset`` calls right after this inside ``reset_context``.

        Raises:
            NotImplementedError: a keyframe (the scenes define none).
        """
        if keyframe_id is not None:
            raise NotImplementedError("AuvPhysics has no keyframes: episodes start from the task's draw")

    def after_reset(self) -> None:
        """After the task's ``initialize_episode``: :meth:`bind` the episode's simulation.
        dm_control's ``mj_forward`` here is left out: the task's reset already ran one
        (:meth:`sim.scene.physics.Physics.reset`), and the episode then starts from exactly
        the calls the gymnasium env makes."""
        self.bind()

    def copy(self, share_model: bool = False):
        raise NotImplementedError("AuvPhysics cannot be copied: the simulation's state lives beyond MjData "
                                  "(thrusters, current, navigation filter, mission)")

    def __getstate__(self):
        raise TypeError("AuvPhysics cannot be pickled: the simulation's state lives beyond MjData")

    # ------------------------------------------------------------------ named readouts
    def vehicle_truth(self) -> VehicleTruth:
        """The AUV's true state now (:meth:`sim.scene.physics.Physics.truth`)."""
        return self._sim.truth()

    def pos_ned(self) -> np.ndarray:
        """(3,) true position of the vehicle origin (CO), NED, m."""
        return self._sim.truth().pos_ned

    def rpy_rad(self) -> np.ndarray:
        """(3,) true roll, pitch, yaw (ZYX Euler angles of body FRD in NED), rad."""
        return self._sim.truth().rpy_rad

    def nu_body(self) -> np.ndarray:
        """(6,) true body velocity over ground [u, v, w] m/s and [p, q, r] rad/s, FRD."""
        return self._sim.truth().nu

    def velocity_body_mps(self) -> np.ndarray:
        """(3,) true linear velocity over ground [u, v, w], body FRD, m/s."""
        return self.nu_body()[:3]

    def rates_body_radps(self) -> np.ndarray:
        """(3,) true angular rates [p, q, r], body FRD, rad/s."""
        return self.nu_body()[3:]

    def depth_m(self) -> float:
        """True depth of the vehicle origin (NED z), m."""
        return float(self.pos_ned()[2])

    def altitude_m(self) -> float:
        """True height of the vehicle origin above the seabed beneath it, m."""
        n, e, d = self.pos_ned().tolist()
        return float(self._sim.world.seabed.depth_at(n, e)) - d

    def time_s(self) -> float:
        """Time since the episode's start, s (as :meth:`time`)."""
        return self.time()
