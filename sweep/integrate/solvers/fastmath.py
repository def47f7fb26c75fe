"""The fastmath flags of every compiled kernel."""

FAST = {"nsz": True, "arcp": True, "contract": True, "afn": True}
"""FMA contraction and reciprocal division (~9 % faster), but no "nnan" or "ninf" (the status codes rely on
isfinite) and no "reassoc" (results stay reproducible on one instruction set). A dict, not a set: numba pickles the
options into the cache key of closures, and a set of strings pickles in a per-process order (string hashing is
randomised), which made those kernels miss the disk cache."""
