"""Onboard autonomy: what would run on the vehicle.

Never imports ``mujoco``, ``sim`` or ``rerun``: it consumes sensor messages
(:mod:`autonomy.messages`) and emits commands.
"""
