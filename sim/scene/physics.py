"""The simulated world in one object: MuJoCo scene, vehicle dynamics, current and ray caster.

:class:`Physics` is what the mission loop, the gym environments, the physics benchmark and
the scene tests step. Per physics step (:meth:`Physics.step`): the thrusters and the
hydrodynamic wrench are updated with the present current (:meth:`VehicleDynamics.step_inputs`),
MuJoCo integrates one step, the clock advances and the current evolves. The clock is the
step count times the step (``t_s = n dt``), not a running sum, so it does not drift.

More than one vehicle: the scenario's ``vehicle`` is the AUV (``physics.vehicle``, the
default of every readout); ``scenario.vehicles`` adds surface vessels
(:class:`sim.dynamics.surface_vessel.SurfaceVesselDynamics`) stepped on the same clock in the same
current, each holding the thruster command last given with :meth:`Physics.set_command`;
their forces are updated at :data:`EXTRA_WRENCH_RATE_HZ` and held in between.
``physics.vehicles`` maps ``"auv"`` and each extra name to its dynamics.
"""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from scenarios.config.world import CurrentConfig
from scenarios.schema import Scenario
from sim.dynamics.current import OceanCurrent
from sim.rng import component_rng
from sim.sensors.base import SceneView
from sim.sensors.raycast import MujocoRayCaster
from sim.dynamics.truth import VehicleTruth
from sim.dynamics.vehicle import VehicleDynamics
from sim.scene.movers import MovingBodies
from sim.dynamics.surface_vessel import SurfaceVesselDynamics
from scenarios.vehicle_params import VehicleParams, load_params_file, load_vehicle_params, params_path
from sim.scene.world import SceneObject, World, build_world

FloatArray = NDArray[np.float64]
#: Rate at which surface vessels' hydrodynamic and thruster forces are updated, Hz.
EXTRA_WRENCH_RATE_HZ = 50.0


class Physics:
    """The scenario's world and vehicle, stepped on one clock.

    Args:
        scenario: the validated scenario (scene, vehicle, current, physics rate).
        seed: root seed of the current's random part (default: the scenario's).

    Attributes:
        world: compiled scene and its tables (objects, seabed, hull sites).
        model, data: the MuJoCo model and data.
        params: the vehicle's parameters.
        vehicle: the AUV's dynamics bound to ``model`` / ``data``.
        extras: name -> dynamics of each extra vehicle (``scenario.vehicles``), in order.
        vehicles: ``{"auv": vehicle, **extras}``.
        current: the water current acting on the vehicle.
        movers: the moving targets (mocap bodies) and their seeded trajectories.
        caster: ray caster over the acoustic geoms (the hull excluded).
        dt_s: physics step, s.
        n_steps: physics steps since :meth:`reset`.
        t_s: simulated time since :meth:`reset`, s (``n_steps * dt_s``).
    """

    def __init__(self, scenario: Scenario, *, seed: int | None = None) -> None:
        self.scenario = scenario
        self.params: VehicleParams = load_vehicle_params(scenario.vehicle)
        self.world: World = build_world(scenario)
        self.model, self.data = self.world.model, self.world.data
        self.dt_s = float(self.model.opt.timestep)
        self.caster = MujocoRayCaster(self.model, self.data, self.world.geom_object_id,
                                      self.world.geom_reflectivity, self.world.vehicle_body_id,
                                      backend=scenario.physics.ray_caster)
        self.vehicle = VehicleDynamics(self.model, self.data, self.params, None, body_id=self.world.vehicle_body_id)
        self.extras: dict[str, SurfaceVesselDynamics] = {
            name: SurfaceVesselDynamics(self.model, self.data, load_params_file(params_path(cfg.preset)),
                                        self.world.extra_body_ids[name])
            for name, cfg in scenario.vehicles.items()}
        self.vehicles: dict[str, VehicleDynamics | SurfaceVesselDynamics] = {"auv": self.vehicle, **self.extras}
        self._extra_list = tuple(self.extras.values())
        # Surface vessels' wrench: updated every `_extra_every` physics steps (at about
        # EXTRA_WRENCH_RATE_HZ) and held in between; their fastest mode (rotor lag 0.2 s,
        # damping time constants ~1 s) is well resolved at that rate.
        self._extra_every = max(1, int(round(1.0 / (self.dt_s * EXTRA_WRENCH_RATE_HZ))))
        self._extra_dt_s = self._extra_every * self.dt_s
        self._extra_count = 0
        self.current: OceanCurrent
        self.reseed(scenario.seed if seed is None else seed)
        self._moving = self._moving_objects()
        self.n_steps = 0
        self.t_s = 0.0

    # ------------------------------------------------------------------ set-up
    def reseed(self, seed: int) -> None:
        """New current from the scenario's config with ``component_rng(seed, "current")``, and
        new mover trajectories (``component_rng(seed, "mover:<name>")``)."""
        self.set_current(self.scenario.world.current, component_rng(int(seed), "current"))
        self.movers = MovingBodies(self.model, self.scenario.world.movers, int(seed), self.scenario.duration_s,
                                   current=self.current)

    def set_current(self, cfg: CurrentConfig, rng: np.random.Generator | None) -> OceanCurrent:
        """Replace the current (e.g. one drawn per episode); the vehicle uses it from the next step.

        Raises:
            ValueError: a random current without a generator.
        """
        self.current = OceanCurrent(cfg, rng)
        self.vehicle.set_current(self.current)
        for extra in self._extra_list:
            extra.set_current(self.current)
        if getattr(self, "movers", None) is not None:
            self.movers.set_current(self.current)  # the bubbles drift with the water
        return self.current

    def reset(self, pos_ned: ArrayLike, rpy_rad: ArrayLike) -> None:
        """Clock to 0, MuJoCo state cleared, vehicle at rest at ``pos_ned`` (m, NED) with
        attitude ``rpy_rad``, current back to its mean; extra vehicles at rest at their
        configured starts (``initial_pos_ne_m``, ``initial_heading_deg``), commands zero."""
        mujoco.mj_resetData(self.model, self.data)
        self.current.reset()
        self.vehicle.reset(pos_ned, rpy_rad)
        for name, extra in self.extras.items():
            cfg = self.scenario.vehicles[name]
            extra.reset(cfg.initial_pos_ne_m, np.deg2rad(cfg.initial_heading_deg))
        self._extra_count = 0
        if self.movers:
            self.movers.apply(self.data, 0.0)
        mujoco.mj_forward(self.model, self.data)
        self.n_steps = 0
        self.t_s = 0.0

    # ------------------------------------------------------------------ stepping
    def step(self, thruster_cmd: ArrayLike) -> None:
        """One physics step with the AUV's normalised thruster commands (n_thr,) in [-1, 1]
        (extra vehicles: their held commands); :meth:`advance` by one step, without the
        contact check."""
        self.advance(thruster_cmd, 1, check_contact=False)

    def advance(self, thruster_cmd: ArrayLike, n_steps: int, *, check_contact: bool = True) -> bool:
        """``n_steps`` physics steps holding the AUV's ``thruster_cmd`` (extra vehicles: their
        held commands); True if the AUV touched anything on any of them (always False with
        ``check_contact`` False)."""
        step_inputs, mj_step, current_step = self.vehicle.step_inputs, mujoco.mj_step, self.current.step
        model, data, dt = self.model, self.data, self.dt_s
        contact = False
        movers = self.movers if self.movers else None
        step_extras = self._step_extras if self._extra_list else None
        for _ in range(n_steps):
            step_inputs(thruster_cmd, dt)
            if step_extras is not None:
                step_extras()
            if movers is not None:
                movers.apply(data, self.t_s)
            mj_step(model, data)
            self.n_steps += 1
            self.t_s = self.n_steps * dt
            current_step(dt)
            if check_contact and data.ncon and not contact:
                contact = self.vehicle_in_contact()
        return contact

    def _step_extras(self) -> None:
        """Update the extra vehicles' joint forces on every ``_extra_every``-th step (held
        by MuJoCo in ``qfrc_applied`` in between), their rotors advanced by the whole hold."""
        if self._extra_count == 0:
            for extra in self._extra_list:
                extra.step_inputs(self._extra_dt_s)
        self._extra_count = (self._extra_count + 1) % self._extra_every

    # ------------------------------------------------------------------ readouts
    def set_command(self, name: str, thruster_cmd: ArrayLike) -> None:
        """Hold normalised thruster commands for extra vehicle ``name`` from the next step on.

        Raises:
            KeyError: no extra vehicle of that name (the AUV's commands go to :meth:`step`).
            ValueError: wrong number of commands.
        """
        self._extra(name).set_command(thruster_cmd)

    def truth(self, name: str = "auv") -> VehicleTruth:
        """True state now of the AUV (default) or of the extra vehicle ``name``.

        Raises:
            KeyError: unknown vehicle name.
        """
        if name == "auv":
            return self.vehicle.truth(self.t_s)
        return self._extra(name).truth(self.t_s)

    def _extra(self, name: str) -> SurfaceVesselDynamics:
        try:
            return self.extras[name]
        except KeyError:
            raise KeyError(f"no vehicle {name!r}; vehicles: {', '.join(self.vehicles)}") from None

    def scene(self, t_s: float | None = None) -> SceneView:
        """What sensors see at ``t_s`` (default: now): the ray caster and the scene objects
        with the movers placed at that time (placed first: ``mj_step`` leaves geom poses at
        the start of the step). A time within the last step is a sensor firing between two
        steps; the vehicles' own bodies stay where the step left them (the hull is not in
        the caster; other vehicles' hulls are off by at most their motion in one step), and
        the next step places the movers again."""
        t = self.t_s if t_s is None else float(t_s)
        if self.movers:
            self.movers.apply(self.data, t)
            mujoco.mj_kinematics(self.model, self.data)
        return SceneView(t, self.caster, self.objects())

    def objects(self) -> tuple[SceneObject, ...]:
        """Scene objects with their present centroid and base (objects on moving bodies follow them)."""
        if not self._moving:
            return self.world.objects
        objs = list(self.world.objects)
        xpos, xmat = self.data.geom_xpos, self.data.geom_xmat
        for i, gid, c_local, b_local in self._moving:
            R = xmat[gid].reshape(3, 3)
            objs[i] = replace(objs[i], centroid_ned=xpos[gid] + R @ c_local, base_ned=xpos[gid] + R @ b_local)
        return tuple(objs)

    def vehicle_in_contact(self) -> bool:
        """True when a contact involves the AUV's body."""
        body = self.model.geom_bodyid
        vb = self.world.vehicle_body_id
        for i in range(self.data.ncon):
            c = self.data.contact[i]
            if body[c.geom1] == vb or body[c.geom2] == vb:
                return True
        return False

    def vehicles_in_contact(self) -> list[tuple[str, str]]:
        """Pairs of vehicle names (``"auv"`` and the extras) whose hulls touch now."""
        body_name = {self.world.vehicle_body_id: "auv"}
        body_name.update({bid: name for name, bid in self.world.extra_body_ids.items()})
        body = self.model.geom_bodyid
        pairs = set()
        for i in range(self.data.ncon):
            c = self.data.contact[i]
            a, b = body_name.get(int(body[c.geom1])), body_name.get(int(body[c.geom2]))
            if a is not None and b is not None and a != b:
                pairs.add(tuple(sorted((a, b))))
        return sorted(pairs)

    def site_pos_body(self, name: str) -> FloatArray:
        """(3,) FRD offset of hull site ``name`` from the body origin, m. Raises ``KeyError``."""
        return self.world.site_pos_body(name)

    def warnings(self) -> int:
        """Number of MuJoCo warnings raised so far."""
        return int(sum(int(w.number) for w in self.data.warning))

    # ------------------------------------------------------------------ internals
    def _moving_objects(self) -> list[tuple[int, int, FloatArray, FloatArray]]:
        """(index, geom id, centroid and base in the geom frame) of objects not fixed to the world."""
        out = []
        for i, obj in enumerate(self.world.objects):
            gid = obj.geom_id
            if gid < 0 or self.model.geom_bodyid[gid] == 0:
                continue
            R0 = self.data.geom_xmat[gid].reshape(3, 3)
            p0 = self.data.geom_xpos[gid]
            out.append((i, gid, R0.T @ (obj.centroid_ned - p0), R0.T @ (obj.base_ned - p0)))
        return out
