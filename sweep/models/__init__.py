"""Right-hand sides and observables of each protocol (numba), one module per protocol."""
