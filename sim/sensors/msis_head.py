"""The scanning head of a mechanically scanned sonar: where it points at each ping.

A full turn (``sector_width_grad == 400``) steps by ``step_grad`` in one direction forever; a
narrower sector ``[centre - width / 2, centre + width / 2]`` is swept back and forth: the head
steps to the limit (a last, shorter step if the width is not a multiple of the step), then
reverses ([Ping360]: "for non-full sectors the scan angle bounces back and forth within the
sector boundaries"). Angles are gradians in ``[0, 400)``.
"""

from __future__ import annotations

from autonomy.msis.ping360 import GRAD_PER_TURN


class HeadSweep:
    """Head angle sequence of one sonar.

    Args:
        step_grad: step per ping (gradians, >= 1).
        sector_width_grad: swept width (gradians, 1..400; 400 = continuous turn).
        sector_centre_grad: centre of the sector (gradians).

    Raises:
        ValueError: a step below 1, or a width outside 1..400 or below the step (sector).
    """

    def __init__(self, step_grad: int, sector_width_grad: int = GRAD_PER_TURN, sector_centre_grad: float = 0.0) -> None:
        if step_grad < 1:
            raise ValueError(f"step_grad must be >= 1, got {step_grad}")
        if not 1 <= sector_width_grad <= GRAD_PER_TURN:
            raise ValueError(f"sector_width_grad must lie in 1..{GRAD_PER_TURN}, got {sector_width_grad}")
        self.full_turn = sector_width_grad >= GRAD_PER_TURN
        if not self.full_turn and sector_width_grad < step_grad:
            raise ValueError(f"sector_width_grad ({sector_width_grad}) must be >= step_grad ({step_grad})")
        self.step_grad = int(step_grad)
        self.width_grad = float(sector_width_grad)
        self.start_grad = float(sector_centre_grad) - (0.0 if self.full_turn else 0.5 * sector_width_grad)
        self.reset()

    def reset(self) -> None:
        """Back to the sector start (full turn: the centre), sweeping clockwise."""
        self._offset = 0.0
        self._direction = 1
        self._first = True

    @property
    def direction(self) -> int:
        """+1 clockwise, -1 anticlockwise (the direction of the next step)."""
        return self._direction

    def peek_angle(self) -> float:
        """The angle :meth:`next_angle` would give, without stepping."""
        saved = (self._offset, self._direction, self._first)
        angle = self.next_angle()
        self._offset, self._direction, self._first = saved
        return angle

    def next_angle(self) -> float:
        """Angle of the next ping, gradians in [0, 400); the first call gives the start."""
        if self._first:
            self._first = False
        elif self.full_turn:
            self._offset = (self._offset + self.step_grad) % GRAD_PER_TURN
        else:
            nxt = self._offset + self._direction * self.step_grad
            if nxt > self.width_grad or nxt < 0.0:
                at_limit = self._offset in (0.0, self.width_grad)
                if at_limit:
                    self._direction = -self._direction
                    nxt = self._offset + self._direction * self.step_grad
                else:
                    nxt = self.width_grad if self._direction > 0 else 0.0
            self._offset = min(max(nxt, 0.0), self.width_grad)
        return (self.start_grad + self._offset) % GRAD_PER_TURN
