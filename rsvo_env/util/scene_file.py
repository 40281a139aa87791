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

from rsvo_env.util.validation import shown

# the most values (numbers, strings, lists, mappings) a document may hold once YAML's aliases
# are expanded: a scene of 100,000 agents fits, a file of nested aliases that would expand to
# gigabytes does not
MAX_VALUES = 1_000_000


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader with YAML 1.2's floats: ``1e9`` and ``1E-3`` are numbers, as a user
    writes them (YAML 1.1, which PyYAML follows, reads them as strings without a dot); a key
    given twice in one mapping is refused, as YAML 1.2 requires."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set[Any] = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if isinstance(key, (str, int, float, bool)) and key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"the key {shown(key)} is given twice", key_node.start_mark
                )
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


def load_yaml(text: Any) -> Any:
    """A YAML document (a string or a file), numbers read as YAML 1.2 reads them; ``ValueError``
    where it repeats a key, refers to itself, or holds more than ``MAX_VALUES`` values once its
    aliases are expanded (``yaml.YAMLError`` where it is not YAML)."""
    document = yaml.load(text, Loader=_Loader)  # noqa: S506  (a SafeLoader)
    check_size(document)
    return document


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """JSON's object hook: a key given twice is refused."""
    seen: set[str] = set()
    for k, _ in pairs:
        if k in seen:
            raise ValueError(f"the key {shown(k)} is given twice")
        seen.add(k)
    return dict(pairs)


def check_size(document: Any) -> int:
    """The number of values ``document`` holds with every shared part counted where it is used
    (YAML's aliases expanded); ``ValueError`` past ``MAX_VALUES`` or where a part contains
    itself. Each distinct list or mapping is counted once and its count reused."""
    counted: dict[int, int] = {}
    open_parts: set[int] = set()

    def size(value: Any) -> int:
        if not isinstance(value, (list, dict)):
            return 1
        key = id(value)
        if key in counted:
            return counted[key]
        if key in open_parts:
            raise ValueError("the document refers to itself (a recursive alias)")
        open_parts.add(key)
        total = 1
        for item in value.values() if isinstance(value, dict) else value:
            total += size(item)
            if total > MAX_VALUES:
                raise ValueError(
                    f"the document holds more than {MAX_VALUES:,} values once its aliases are "
                    "expanded"
                )
        open_parts.discard(key)
        counted[key] = total
        return total

    return size(document)


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
        if path.suffix.lower() == ".json":
            scene = json.loads(text, object_pairs_hook=_unique_keys)
        else:
            scene = load_yaml(text)
    except (json.JSONDecodeError, yaml.YAMLError) as err:
        where = " ".join(str(err).split())  # the parser's account, on the error's one line
        kind = path.suffix[1:].upper()
        raise ValueError(f"--scene {path} is not valid {kind}: {where}") from None
    except ValueError as err:  # a repeated key, a recursive alias, a document too large
        raise ValueError(f"--scene {path}: {err}") from None
    except RecursionError:
        raise ValueError(f"--scene {path}: lists or mappings nested too deeply") from None
    if not isinstance(scene, dict) or not all(isinstance(k, str) for k in scene):
        raise ValueError(f"--scene {path}: expected a mapping of the custom scene's keywords")
    return scene
