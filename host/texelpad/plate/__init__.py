"""The physical plate: the resonant tank calculator (the board-side resonance
sweep is hardware/sweep.py)."""
