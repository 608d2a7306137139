"""Sonar simulation parts shared by every ray-cast sonar (forward-looking, scanning, side-scan).

A sonar is assembled from:

* :mod:`~sim.sensors.sonar.ray_fan`: ray sampling. Columns of rays at fixed azimuths, each
  sampled across its elevation aperture in the sonar frame of :mod:`autonomy.sonar_frame`,
  cast through a :class:`sim.sensors.raycast.RayCaster`, with surface edges located by
  bisection.
* echo formation, per beam an echo-versus-range line: scattering and elevation beam
  pattern per ray, segment energies binned in range (:mod:`~sim.sensors.sonar.echo_lines`),
  the azimuth beam pattern (:mod:`~sim.sensors.sonar.beam_pattern`), spreading, absorption and
  time-varied gain (:mod:`~sim.sensors.sonar.propagation`), speckle and receiver noise
  (:mod:`~sim.sensors.sonar.speckle`), gain and the dB display mapping
  (:mod:`~sim.sensors.sonar.display`), chained by :class:`~sim.sensors.sonar.echo_chain.EchoChain`.
* :mod:`~sim.sensors.sonar.ground_truth`: per-bin object labels, boxes and visible fractions.

The forward-looking sonar (:class:`sim.sensors.fls.FlsSensor`) is one assembly of these parts.
"""
