"""The QP layer: rows stored by agent and the solvers (the exact batched 2-D projection, the
qpsolvers reference)."""
