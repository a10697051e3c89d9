"""Figures, animations and the browser replay."""
