"""Training nominal policies behind the R-CBF safety filter with Stable-Baselines3.

``python -m training.train`` trains, ``python -m training.evaluate`` evaluates; a YAML config per
scenario lives in ``training/configs/``. Needs the ``train`` extra.
"""
