"""Benchmarks behind ``auvsim bench NAME``: one registry (:data:`BENCHES`), one module each.

Each entry names the module and function to run and a one-line description; the function
takes the scenario (or only a seed, or nothing) and returns a JSON-serialisable dict.
"""

from __future__ import annotations

# name -> (module, function, help)
BENCHES: dict[str, tuple[str, str, str]] = {
    "physics": ("sim.bench.physics", "run", "hull + hydrodynamics + thrusters at the physics rate"),
    "fls": ("sim.bench.fls", "run", "forward-looking sonar frame rendering"),
    "mission": ("sim.bench.mission", "run", "closed-loop mission, sensors and FLS included; time per stage"),
    "pmha": ("sim.bench.pmha", "run", "PMHA world-model update time"),
    "gym": ("sim.bench.gym", "run", "gymnasium environment step rate"),
    "vector": ("sim.bench.vector", "run", "batched Survey env (N = 1, 4, 16, 64) steps per second, CPU and memory, "
                                          "without and with sonar"),
    "tracking": ("sim.bench.tracking", "run", "USBL + sonar target tracker time per 10 Hz tick"),
    "sss": ("sim.bench.sss", "run", "side-scan sonar ping rendering (1000 bins per side)"),
    "msis": ("sim.bench.msis", "run", "scanning sonar pings per second and feature-extraction cost per ping"),
    "link": ("sim.bench.link", "run", "acoustic modem link and message codec: cost per message and per tick"),
    "dataset": ("sim.bench.dataset", "run", "labelled FLS dataset frames per second, one worker process against N"),
    "atr": ("sim.evaluation.atr_metrics", "bench_atr", "ATR inference frame rate (CNN and classical)"),
    "inspection": ("sim.bench.inspection", "run", "inspection planner: CPU per re-plan against the number of objects"),
    "export": ("sim.bench.export", "run", "CPU per simulated minute of the ROS 2 bag, XTF and ping-protocol writers"),
}
