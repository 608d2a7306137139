"""Simulated sensors: one contract (:mod:`sim.sensors.base`), registered by kind
(:mod:`sim.sensors.registry`)."""
