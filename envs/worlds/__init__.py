"""Worlds: corridor layouts, the PyBullet builder, geometry checks, and the seeded generator
with its settings and visibility guarantee."""
