"""The continuous-connectivity paper (Nestmeyer et al.), one sub-package per idea.

:mod:`tether.continuous.connectivity`: the connectivity force of App. A (lambda2 and its
gradient, the estimator, the robot model and its integrator) and the ``connectivity``
strategy. :mod:`tether.continuous.exploration`: the decentralized multi-target
exploration of Secs. 3-4 built on that force (Algorithms 1 and 2) and the
``multi_target`` strategy.
"""
