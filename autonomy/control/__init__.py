"""Control: PID autopilots producing a desired body wrench, and the thrust allocation."""
