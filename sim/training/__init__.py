"""Training of the ATR detector (torch, imported lazily; install with the ``train`` extra)."""

TORCH_HINT = "ATR training needs torch: pip install 'auvsim[train]' (or pip install torch)"


def require_torch():
    """Import and return torch, or raise ImportError with the install hint."""
    try:
        import torch
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(TORCH_HINT) from exc
    return torch
