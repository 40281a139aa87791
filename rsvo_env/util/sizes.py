"""The sizes at which the library changes its method, in one place, each named for what it
bounds and measured where its comment says. Read as ``sizes.NAME`` where used (not imported by
value), so that a test may move one."""

# Agents an env up to which every pair is examined: below it, all pairs cost less than a grid
# or KD-tree search (benchmarks/speed/knn_speed.py).
ALL_PAIRS_MAX_AGENTS = 64

# Agents an env up to which the filter takes its compiled all-pairs pass rather than the pair
# search, row packing and batched solve (benchmarks/speed/dense_filter_speed.py). With equal scores,
# the scenarios' default, the two break even at 256; with scores spread over 1..10 the general
# path's wider search lets the dense pass win up to about 450.
COMPILED_FILTER_MAX_AGENTS = 256

# Agents an env up to which the (N, N) weight matrix is kept (8 MB per env at 1,024); beyond
# it the weights are computed from the scores where they are read.
WEIGHT_MATRIX_MAX_AGENTS = 1024

# Independent QPs a call below which a parallel launch costs more than the work (measured:
# benchmarks/results/contention.md, kernel section).
PARALLEL_MIN_PROBLEMS = 256

# Agents a call from which a kernel's prange form, run on one thread, beats its serial form:
# numba compiles a prange body as a function of its own whose arrays it marks free of aliasing
# (parfor lowering), and the compiler then keeps the inner loops' values in registers. On one
# thread a launch costs about 1 us and waits for no other thread, so it cannot stall under
# load. Measured for the dense filter pass and the CSR solve: benchmarks/results/kernel_forms.md.
PRANGE_FORM_MIN_AGENTS = 64

# Which k-nearest-neighbour kernel serves which batch (measured with benchmarks/speed/knn_speed.py,
# one thread, on positions drifting as an env steps them). Insertion costs ~n^2 k with a branch
# per candidate, which the predictor learns while a step's E n agents are few and their order
# changes little; ranking ~n^3 per env whatever k, without branches; the env-lanes kernel
# inserts branch-free into all envs at once, vectorised across envs, with a fixed cost per
# (agent, neighbour, slot) that only many envs amortise.
KNN_INSERTION_MAX_AGENTS = 512
KNN_LANES_MIN_ENVS = 64
KNN_RANKED_MIN_AGENTS, KNN_RANKED_MAX_AGENTS = 8, 32

# Exempt agents (the filter's search by the nominal) up to which each scans its env; more
# share the grid search.
EXEMPT_SCAN_MAX_AGENTS = 64
