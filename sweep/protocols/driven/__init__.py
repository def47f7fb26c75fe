"""The driven protocol: the drive keeps moving at V; steady sliding or stick-slip (docs/physics.md 3b)."""
