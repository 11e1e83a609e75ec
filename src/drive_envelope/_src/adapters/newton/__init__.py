"""Newton adapter: the envelope as a ``newton.actuators`` clamping stage (Newton imported lazily)."""
