"""The crowd sizes at which the library changes its method, in one place (each measured where
its comment says)."""

# Agents an env up to which every pair is examined: below it, all pairs cost less than a grid
# or KD-tree search (benchmarks/knn_speed.py).
DENSE_MAX_AGENTS = 64

# Agents an env up to which the filter takes its compiled all-pairs pass rather than the pair
# search, row packing and batched solve (benchmarks/dense_filter_speed.py). With equal scores,
# the scenarios' default, the two break even at 256; with scores spread over 1..10 the general
# path's wider search lets the dense pass win up to about 450.
DENSE_KERNEL_MAX_AGENTS = 256

# Agents an env up to which the (N, N) weight matrix is kept (8 MB per env at 1,024); beyond
# it the weights are computed from the scores where they are read.
WEIGHT_MATRIX_MAX_AGENTS = 1024
