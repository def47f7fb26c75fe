"""Fitting the friction parameters to measured stop transients and relaxed slips (docs/fit.md).

The forward model is the sweep engine (:mod:`sweep.fit.forward`): every parameter set a fit needs at one moment
(all curves, all finite-difference perturbations, all profile points) is one flat batch of points.
"""
