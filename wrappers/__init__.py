"""PettingZoo and Gymnasium wrappers around the rsvo_env core."""
