"""REMUS 100 preset: steady surge speed vs propeller rpm against Fossen's MSS library figures (docs/references.md [FossenMSS]).

The reference table comes from Fossen's REMUS 100 simulator, whose propeller thrust
depends on the advance speed. Assumptions of that model, restated here:

* thrust ``X = (1 - t) rho D^4 [K_T0 n^2 + (K_Tmax - K_T0) / J_max (V_a / D) n]`` for
  n > 0 (rps), propeller diameter D = 0.14 m, thrust deduction t = 0.1,
  K_T0 = 0.4566, K_Tmax = 0.1798, J_max = 0.6632 (Wageningen B-series, P/D = 0.8),
  advance speed V_a = 0.944 U;
* surge damping: hull drag 0.5 rho C_D0 A U^2 with C_D0 = 0.42 on the frontal disc
  A = pi (D_hull / 2)^2, plus linear damping (m - X_udot) / 20 s fading as exp(-3 U).

Our preset carries the same damping (quadratic 6.109, linear 1.5935 with decay 3 s/m), so
with the propeller law applied through the thruster input the MuJoCo hull should settle
at the table's speeds. The test drives the full stack (thruster command -> thrust ->
Fossen wrench -> mj_step) at the reference simulator's 50 Hz.
"""

from __future__ import annotations

import math

import mujoco
import pytest

from scenarios.config.vehicle import ThrusterOverrides, VehicleConfig
from sim.dynamics.hull import build_standalone_spec
from sim.dynamics.vehicle import VehicleDynamics
from scenarios.vehicle_params import load_vehicle_params

RHO, D_PROP, T_DED = 1026.0, 0.14, 0.1
KT0, KT_MAX, J_MAX, WAKE = 0.4566, 0.1798, 0.6632, 0.944
TABLE = [(300, 0.486), (500, 0.831), (800, 1.338), (1000, 1.674), (1200, 2.009), (1525, 2.554)]


def propeller_thrust_n(rpm: float, speed_mps: float) -> float:
    n = rpm / 60.0
    va = WAKE * speed_mps
    return (1 - T_DED) * RHO * D_PROP ** 4 * (KT0 * n * n + (KT_MAX - KT0) / J_MAX * (va / D_PROP) * n)


@pytest.mark.parametrize("rpm, speed_ref", TABLE)
def test_remus_steady_speed_matches_reference_table(rpm, speed_ref):
    p = load_vehicle_params(VehicleConfig(model="remus100",
                                          thrusters=ThrusterOverrides(time_constant_s=0.0)))
    assert p.n_thrusters == 1 and p.layout.curve_exponent[0] == 2.0 and p.layout.dead_zone[0] == 0.0
    model = build_standalone_spec(p, timestep_s=0.02).compile()
    data = mujoco.MjData(model)
    dyn = VehicleDynamics(model, data, p)
    dyn.reset([0.0, 0.0, 10.0], [0.0, 0.0, 0.0])
    f_max = p.layout.max_fwd_n[0]
    u = 0.0
    for _ in range(int(80.0 / 0.02)):
        f = propeller_thrust_n(rpm, u)
        dyn.step_inputs([math.sqrt(min(max(f, 0.0) / f_max, 1.0))], 0.02)
        mujoco.mj_step(model, data)
        u = float(dyn.nu()[0])
    assert u == pytest.approx(speed_ref, rel=0.01)
