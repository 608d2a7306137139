"""Simulated sensors. Each has a name, a rate, a latency and ``measure(truth, *, noise=True)``."""
