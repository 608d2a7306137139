"""Typed sub-configs, one module per component area; composed in :mod:`scenarios.schema`."""
