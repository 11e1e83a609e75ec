"""The test stand: one actuated joint simulated with PhysX's drive and envelope semantics."""
