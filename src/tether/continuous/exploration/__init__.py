"""Decentralized multi-target exploration under continuous connectivity (Secs. 3-4).

Targets and their generators, paths for the control loop, the roles and planning of
Algorithm 1, the traveling forces of Algorithm 2, the prime traveler's election and the
consensus on its efficiency, helpers of a stalled prime, the reference filter of eq.
(16), and the ``multi_target`` strategy, which runs on
:mod:`tether.continuous.connectivity`.
"""
