"""Update-time deleter (the deleter role): forgets tentative states left unmeasured too long."""

from __future__ import annotations


class UpdateTimeDeleter:
    """Deletes a state unmeasured for more than ``max_age_s`` seconds while it has fewer than
    ``min_updates`` measurements (``min_updates`` None: whatever its count).

    Raises:
        ValueError: ``max_age_s`` not positive or ``min_updates`` < 1.
    """

    def __init__(self, max_age_s: float, min_updates: int | None = None) -> None:
        if not max_age_s > 0.0 or (min_updates is not None and min_updates < 1):
            raise ValueError(f"UpdateTimeDeleter needs max_age_s > 0 and min_updates >= 1, "
                             f"got {max_age_s}, {min_updates}")
        self.max_age_s = float(max_age_s)
        self.min_updates = min_updates

    def deletes(self, t_s: float, t_last_update_s: float, n_updates: int) -> bool:
        """Whether a state last measured at ``t_last_update_s`` with ``n_updates``
        measurements is deleted at time ``t_s``."""
        tentative = self.min_updates is None or n_updates < self.min_updates
        return tentative and t_s - t_last_update_s > self.max_age_s
