"""Batched backends of the envelope (Warp, Newton, PyTorch); each module imports its engine lazily."""
