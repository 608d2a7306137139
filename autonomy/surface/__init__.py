"""Surface-vessel autonomy (the moving buoy): GNSS + compass navigation, station keeping
and following a point (the AUV) at a horizontal offset."""
