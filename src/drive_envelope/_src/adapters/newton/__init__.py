"""Newton adapter: the envelope as a ``newton.actuators`` clamping stage, and the glue Newton needs.

``clamp`` defines ``ClampingPerformanceEnvelope`` (on first use: it subclasses Newton's
``ClampingBase``); ``usd`` adds it, with ``DrivePD``, for every envelope of a USD asset after
``ModelBuilder.add_usd`` (``add_envelopes_from_usd``); ``bias`` computes the gravity and Coriolis
bias the implicit effort mode needs; ``stand`` is the test stand on Newton (``simulate --engine
newton``). Newton and Warp are imported inside functions only; the public entry point is
:mod:`drive_envelope.newton`.
"""
