"""MuJoCo adapter internals: the plugin build, its loader, MjSpec helpers and the test stand."""
