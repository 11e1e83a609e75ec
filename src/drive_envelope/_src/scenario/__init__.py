"""Test-stand scenarios and trajectories: the data model and its files (no engine)."""
