"""Onboard autonomy: what would run on the vehicle.

Never imports ``mujoco``, ``sim``, ``rerun`` or ``scenarios``: it consumes sensor messages
(:mod:`autonomy.messages`), emits commands and owns its config classes.
"""
