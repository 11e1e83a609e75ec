"""Isaac Lab adapter: explicit actuators on PyTorch with the envelope as their effort clip."""
