"""The sensing layer: who senses whom, communication links, depth sensors.

* :mod:`tether.sensing.robots` -- robots sensing robots: range, line of
  sight, occlusion by robot bodies, bounded noise (the interaction graph);
* :mod:`tether.sensing.links` -- communication link models on occupancy grids
  (registered in ``LINK_MODELS``: ``los``, ``disk``);
* :mod:`tether.sensing.depth` -- a depth sensor by ray casting on a grid.
"""

from tether.sensing.robots import NoiseKind, Observation, SensorModel, sense, sensed_pairs

__all__ = ["NoiseKind", "Observation", "SensorModel", "sense", "sensed_pairs"]
