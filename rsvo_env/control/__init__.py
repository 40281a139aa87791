"""Scripted control: move-to-goal, R-ORCA, residual actions, theta as an action, the stall clock."""
