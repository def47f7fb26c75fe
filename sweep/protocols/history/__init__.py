"""The history protocol: a piecewise load history (velocity steps, holds, slide-hold-slide) at every point."""
