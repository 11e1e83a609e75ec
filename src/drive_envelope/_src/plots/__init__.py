"""Envelope plots: curve data (NumPy) and the matplotlib figure (imported lazily)."""
