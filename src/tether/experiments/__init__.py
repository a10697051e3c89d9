"""Experiments: parameter grids x seeds, executors, reports."""
