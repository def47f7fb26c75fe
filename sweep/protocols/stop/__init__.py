"""The stop protocol: steady sliding at V, the drive frozen at t = 0, the slider relaxes (docs/physics.md 3a)."""
