"""Private implementation of drive_envelope. Import from the public modules instead."""
