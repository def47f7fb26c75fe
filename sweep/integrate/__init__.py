"""Per-point drivers (model x stepper x controller x recorder), the SIMD lanes and the batch loops over points."""
