"""Mine-countermeasures survey (paper 003): INS drift, tile-level ATR detections, the fast
kinematic survey and its Monte Carlo figures."""
