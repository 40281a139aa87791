"""The safety filter: its configuration, inputs, result, statistics, the culling by the nominal,
and ``SafetyFilter``."""
