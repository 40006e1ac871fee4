"""The tilt reflex: a tipping trunk raises the stance watch's alarm.

Settings (:class:`~footfall.control.reflexes.ReflexConfig`): ``tilt_reflex``
(the switch) and ``tilt_threshold`` [rad]. The alarm stops the body and
brings a swinging foot down at once; the recovery
(:mod:`footfall.control.reflexes.recovery`) then waits for the posture.
"""

from __future__ import annotations

import numpy as np

from footfall.control.reflexes import ReflexConfig, tilt_error


class TiltReflex:
    """Watch the trunk's roll and pitch against the planned attitude."""

    def __init__(self, config: ReflexConfig) -> None:
        self.on = config.tilt_reflex
        self.threshold = config.tilt_threshold  # [rad]

    def watch(self, measured_rpy: np.ndarray, desired_rpy: np.ndarray, recovering: bool
              ) -> float | None:
        """The roll or pitch error [rad] that sets the reflex off, or None.

        ``measured_rpy``, ``desired_rpy`` (3,) [rad]; ``recovering``: the posture is already
        being recovered after an alarm (a tilt then does not set the reflex off again).
        """
        error = tilt_error(measured_rpy, desired_rpy) if self.on else 0.0
        return error if error > self.threshold and not recovering else None
