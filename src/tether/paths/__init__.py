"""Paths: reference trajectories, grid search and splines."""
