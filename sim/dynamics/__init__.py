"""Vehicle and water dynamics: the hull in MuJoCo, Fossen hydrodynamics, thrusters, the ocean current, the surface vessel, and the true state they produce."""
