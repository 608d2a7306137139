"""Communication channels between the scene's vehicles (:mod:`sim.comms.acoustic_link`)."""

from sim.comms.acoustic_link import AcousticLink, LinkStats, Packet

__all__ = ["AcousticLink", "LinkStats", "Packet"]
