"""Monte Carlo sweeps: many seeded runs of a scenario, resumable, in parallel."""
