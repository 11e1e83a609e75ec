"""Datasheet-to-sim: the four envelope parameters from motor, gear and controller datasheets."""
