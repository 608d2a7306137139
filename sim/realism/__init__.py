"""Sonar realism: real frames against the simulator's, measured by one report (``auvsim realism``)."""
