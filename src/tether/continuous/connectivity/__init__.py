"""The connectivity force of App. A and the ``connectivity`` strategy.

Table 2's parameters, the weighted graph and its potential, the gradient of lambda2 and
the force (eqs. (17)-(18)), the decentralized estimator, the robot of eq. (1) and its
integrator, external forces and safe start placements, with their compiled kernels.
"""
