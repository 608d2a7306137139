"""Messages the vehicles exchange over the acoustic modem: compact, versioned binary layouts
(:mod:`autonomy.comms.messages`) built on shared fixed-point fields (:mod:`autonomy.comms.wire`)."""
