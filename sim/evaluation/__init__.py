"""Evaluation against ground truth, kept out of the online loop: detection matching,
ATR metrics on datasets, world-model scoring (matching and GOSPA)."""
