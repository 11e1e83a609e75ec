"""Sim-to-real analysis: read logs, check them against envelopes, fit envelopes to measurements."""
