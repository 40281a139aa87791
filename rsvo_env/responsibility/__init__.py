"""R-SVO: the responsibility angle and weights of each pair (paper, Sec. III), and the named
weightings."""

from rsvo_env.responsibility.svo import (
    BLOCK_ENTRIES,
    WEIGHTING_MODES,
    Weighting,
    check_weighting,
    min_pair_weight,
    named_weights,
    named_weights_and_floor,
    pair_omega,
    r_svo,
    responsibility_weight,
    scored_weight,
    share_of,
    smallest_weight,
    symmetric_envs,
    theta_for_weight,
    validate_weight_matrix,
    weight_matrix,
)

__all__ = [
    "BLOCK_ENTRIES",
    "WEIGHTING_MODES",
    "Weighting",
    "check_weighting",
    "min_pair_weight",
    "named_weights",
    "named_weights_and_floor",
    "pair_omega",
    "r_svo",
    "responsibility_weight",
    "scored_weight",
    "share_of",
    "smallest_weight",
    "symmetric_envs",
    "theta_for_weight",
    "validate_weight_matrix",
    "weight_matrix",
]
