"""Synthetic, labelled FLS datasets for ATR training and evaluation (``auvsim dataset``)."""
