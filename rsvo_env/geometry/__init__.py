"""Bodies, obstacles, clearance and the pair search (which pairs can interact)."""
