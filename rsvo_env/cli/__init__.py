"""The ``rsvo`` command: the top floor, the one part of ``rsvo_env`` that may import wrappers."""
