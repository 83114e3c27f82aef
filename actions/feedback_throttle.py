"""When a behaviour publishes feedback: at every phase change, and at a steady rate between."""

from __future__ import annotations

import math

#: Feedback period [s] between phase changes: 50 Hz, above the 20 Hz actions promise.
FEEDBACK_PERIOD_S = 0.02


class FeedbackThrottle:
    """Says when feedback is due, so a 1 kHz behaviour does not publish on every tick."""

    def __init__(self, period_s: float = FEEDBACK_PERIOD_S):
        self.period_s = period_s
        self._phase = ""
        self._last_s = -math.inf

    def due(self, now_s: float, phase: str) -> bool:
        """True (and remembered) at a phase change or when a period has passed since the last."""
        if phase == self._phase and now_s - self._last_s < self.period_s - 1e-9:
            return False
        self._phase, self._last_s = phase, now_s
        return True
