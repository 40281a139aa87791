"""The API reference renders for readers: every object ``docs/reference.md`` shows, and every
public method of the classes it shows with their members, has a docstring in Google style
(mkdocstrings' ``docstring_style: google``) that names each parameter; and no Sphinx role is
left in any docstring of the package (they rendered as literal text)."""

from __future__ import annotations

import re

import griffe
import pytest

from tests.support.checkout import ROOT, installed_view

REFERENCE = (ROOT / "docs" / "reference.md").read_text()
# ``::: path`` blocks, with their ``members: [...]`` or ``members: false`` where given
BLOCK = re.compile(r"^::: (\S+)((?:\n    .*)*)", re.M)
ROLE = re.compile(r":(class|func|meth|mod|attr|data|obj|exc):`")


def package() -> griffe.Object:
    return griffe.load(
        "rsvo_env",
        search_paths=[str(installed_view())],
        docstring_parser=griffe.Parser.google,
        try_relative_path=False,
        resolve_aliases=True,
    )


def parameters(obj: griffe.Object) -> list[str]:
    """What a reader passes: a function's parameters, a class's ``__init__``'s (self, and
    ``*args``/``**kwargs`` forwarded unnamed, aside)."""
    if obj.is_class:
        init = obj.members.get("__init__")
        if init is None or init.is_alias:
            return []
        obj = init
    return [p.name for p in obj.parameters if p.name not in ("self", "cls")]


def problems(obj: griffe.Object, name: str) -> list[str]:
    obj = obj.final_target if obj.is_alias else obj
    if obj.docstring is None or not obj.docstring.value.strip():
        return [f"{name}: no docstring"]
    found = [f"{name}: a Sphinx role"] if ROLE.search(obj.docstring.value) else []
    documented = set()
    for section in obj.docstring.parse(griffe.Parser.google):
        if section.kind.value in ("parameters", "other parameters", "attributes"):
            documented |= {p.name.lstrip("*") for p in section.value}
    if obj.is_function or obj.is_class:
        lack = [p for p in parameters(obj) if p.lstrip("*") not in documented]
        found += [f"{name}: parameter {p!r} not documented" for p in lack]
    return found


def shown_objects() -> list[tuple[str, griffe.Object]]:
    pkg = package()
    shown = []
    for path, options in BLOCK.findall(REFERENCE):
        obj = pkg[path.split(".", 1)[1]]
        shown.append((path, obj))
        target = obj.final_target if obj.is_alias else obj
        listed = re.search(r"members: \[([^\]]*)\]", options)
        if listed:
            names = [m.strip() for m in listed.group(1).split(",")]
        elif "members: false" in options or not target.is_class:
            names = []
        else:
            names = [
                m
                for m, member in target.members.items()
                if not m.startswith("_")
                and (member.final_target if member.is_alias else member).is_function
            ]
        shown += [(f"{path}.{m}", target.members[m]) for m in names]
    return shown


def test_every_object_the_reference_shows_is_documented_in_google_style():
    shown = shown_objects()
    assert len(shown) >= 60
    found = [p for name, obj in shown for p in problems(obj, name)]
    assert not found, found


def test_no_sphinx_role_is_left_in_any_docstring():
    offenders = []
    for folder in ("rsvo_env", "wrappers", "training"):
        for path in (ROOT / folder).rglob("*.py"):
            for k, line in enumerate(path.read_text().splitlines(), 1):
                if ROLE.search(line):
                    offenders.append(f"{path.relative_to(ROOT)}:{k}")
    assert not offenders, offenders


@pytest.mark.parametrize(
    "docstring, found",
    [
        ('"""Add.\n\n    Args:\n        a: One.\n        b: Two.\n    """', []),
        ('"""Add.\n\n    Args:\n        a: One.\n    """', ["add: parameter 'b' not documented"]),
        (
            '"""Add :func:`x`."""',
            [
                "add: a Sphinx role",
                "add: parameter 'a' not documented",
                "add: parameter 'b' not documented",
            ],
        ),
    ],
)
def test_the_check_finds_what_it_says(docstring, found):
    module = griffe.visit(
        "m", filepath=ROOT / "m.py", code=f"def add(a, b):\n    {docstring}\n",
        docstring_parser=griffe.Parser.google,
    )  # fmt: skip
    assert problems(module["add"], "add") == found
