"""Training nominal policies behind the R-CBF safety filter with Stable-Baselines3.

``rsvo train`` (``python -m rsvo_env.training.train``) trains, ``rsvo evaluate``
(``python -m rsvo_env.training.evaluate``) evaluates; a YAML config per scenario lives in
``configs/`` beside this file. Needs the ``train`` extra.
"""
