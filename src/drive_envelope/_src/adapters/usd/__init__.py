"""OpenUSD adapter: PhysxDrivePerformanceEnvelopeAPI authoring and reading, the way PhysX reads it.

``stage`` opens assets (or a new layer over one) and turns USD's diagnostics into one-line
messages; ``save`` writes them back atomically and checked; ``authoring`` writes and reads the
envelope in the stage's units; ``articulation`` decides which joints PhysX makes articulation joints;
``instancing`` finds where an edit for a joint inside an instance must go; ``joint_map`` (no ``pxr``)
reads map files for ``usd apply`` and ``mujoco apply``; ``apply`` puts them together for a whole robot.
Everything imports ``pxr`` (usd-core plus the codeless ``physx-usd-schemas``) inside functions only;
the public entry point is :mod:`drive_envelope.usd`.
"""
