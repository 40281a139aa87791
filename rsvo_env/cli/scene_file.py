"""Scene files for ``rsvo simulate custom --scene FILE``: a YAML or JSON mapping of the custom
scene's keywords (``starts``, ``goals``, ``radii``, ``circles``, ``walls``, ``thickness``,
``dynamics``, ``u_max``, ``a_max``, ...; ``docs/scenarios.md``), each checked by the scene
itself. Also the YAML reader the training configs use: numbers as YAML 1.2 reads them."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import yaml


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader with YAML 1.2's floats: ``1e9`` and ``1E-3`` are numbers, as a user
    writes them (YAML 1.1, which PyYAML follows, reads them as strings without a dot)."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


def load_yaml(text: Any) -> Any:
    """A YAML document (a string or a file), numbers read as YAML 1.2 reads them."""
    return yaml.load(text, Loader=_Loader)  # noqa: S506  (a SafeLoader)


SUFFIXES = (".yaml", ".yml", ".json")


def read_scene(path: Path) -> dict[str, Any]:
    """The scene's keywords from ``path``; ``ValueError`` naming the file and what is wrong."""
    if path.suffix.lower() not in SUFFIXES:
        raise ValueError(f"--scene {path}: use a {', '.join(SUFFIXES)} file")
    try:
        text = path.read_text()
    except OSError as err:
        raise ValueError(f"--scene {path}: {err.strerror or err}") from None
    try:
        scene = json.loads(text) if path.suffix.lower() == ".json" else load_yaml(text)
    except (json.JSONDecodeError, yaml.YAMLError) as err:
        where = " ".join(str(err).split())  # the parser's account, on the error's one line
        kind = path.suffix[1:].upper()
        raise ValueError(f"--scene {path} is not valid {kind}: {where}") from None
    if not isinstance(scene, dict) or not all(isinstance(k, str) for k in scene):
        raise ValueError(f"--scene {path}: expected a mapping of the custom scene's keywords")
    return scene
