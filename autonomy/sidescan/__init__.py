"""Onboard side-scan processing: tiles from pings, and the highlight-shadow detector."""
