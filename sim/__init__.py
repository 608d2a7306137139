"""auvsim simulator side: MuJoCo world, vehicle physics, sensors, mission runner."""
