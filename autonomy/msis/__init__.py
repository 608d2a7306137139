"""Mechanically scanned imaging sonar (Ping360 class) on board: device timing, the sonar
buffer, circle and line-segment features and the pool / tank position fixes ([P002])."""
