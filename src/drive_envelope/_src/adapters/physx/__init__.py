"""PhysX adapter: the test stand as a USD stage stepped by real PhysX (the ``ovphysx`` wheel, CPU)."""
