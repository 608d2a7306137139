"""The MuJoCo world: seabed, basin, targets and their meshes, movers, and the physics that steps it."""
