"""OpenUSD authoring and reading of PhysxDrivePerformanceEnvelopeAPI, and the ovphysx runner.

Everything here imports ``pxr`` (usd-core plus the codeless ``physx-usd-schemas``) or ``ovphysx``
inside functions only; the public entry point is :mod:`drive_envelope.usd`.
"""
