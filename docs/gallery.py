"""Writes the site's gallery: a page per registered id (its picture, its GIF, its parameters,
how to make it) and the gallery page that shows them all.

    python docs/gallery.py            # the pages and every picture (about two minutes)
    python docs/gallery.py --pages    # the pages alone (what tests/project/test_docs.py checks)
    python docs/gallery.py --models   # the pictures of scenes with another model (MODEL_SCENES)

The pages come from the code (each scenario's docstring and defaults, the registry's ids and
step limits), so they cannot drift from it: the tests regenerate them and compare. The
pictures are one episode of seed 0, every theta drawn from U(1, 10), under the scenario's own
scripted controller behind the filter (``rsvo_env.cli.episode.run``, which ``rsvo simulate``
runs).
"""

from __future__ import annotations

import argparse
import inspect
from pathlib import Path

DOCS = Path(__file__).resolve().parent
IMAGES = DOCS / "images"
PAGES = DOCS / "scenarios"
# scenes shown with a model other than their default (docs/liveness.md, "Every model")
MODEL_SCENES = (("doorway", "double_integrator"), ("obstacle_field", "unicycle"))


def registered() -> dict[str, str]:
    """Every registered id and its scenario, in the registry's order."""
    from rsvo_env.envs.registration import IDS

    return dict(IDS)


def title(scenario: str) -> str:
    return scenario.replace("_", " ").capitalize()


def scenario_page(env_id: str, scenario: str) -> str:
    """The page of one id, from its scenario's docstring and defaults."""
    from rsvo_env.scenarios import SCENARIOS

    cls = SCENARIOS[scenario]
    about = " ".join(inspect.cleandoc(cls.__doc__ or "").split())
    from rsvo_env import control, dynamics
    from rsvo_env.scenarios.base import COMMON_DEFAULTS

    rows = "\n".join(f"| `{k}` | `{v!r}` |" for k, v in cls.defaults.items())
    own = dynamics.MODELS[cls.dynamics].scenario_defaults
    rows += "".join(f"\n| `{k}` | `{v!r}` |" for k, v in own.items() if k not in cls.defaults)
    # the keywords every scenario takes (the common ones, the controllers' settings), where this
    # one keeps their defaults
    shared = {**COMMON_DEFAULTS, **control.settings()}
    rows += "".join(
        f"\n| `{k}` | `{v!r}` (every scenario's) |"
        for k, v in shared.items()
        if k not in cls.defaults
    )
    if cls.models:
        rows += f"\n| `dynamics` | `{cls.dynamics!r}` (or any of `{cls.models!r}`) |"
        rows += "".join(
            f"\n| `{k}` (with `dynamics={m.name!r}`) | `{v!r}` |"
            for m in dynamics.MODELS.values()
            if m.name != cls.dynamics
            for k, v in m.scenario_defaults.items()
        )
    return f"""# {title(scenario)}: `{env_id}`

{about}

![{title(scenario)}, one episode](../images/{scenario}.gif)

One episode, seed 0, every agent's θ drawn from U(1, 10) (red: egoist, small θ; blue:
altruist), under the scenario's own scripted controller behind the filter
(`rsvo_env.cli.episode.run("{scenario}", theta_range=(1.0, 10.0), gif=...)`, which
`rsvo simulate` runs); its paths:

![{title(scenario)}, the paths of that episode](../images/{scenario}.png)

## Make it

```python
import gymnasium, rsvo_env

env = gymnasium.make("{env_id}")  # one controller for every agent, the filter on
obs, info = env.reset(seed=0)
for _ in range(50):
    obs, reward, terminated, truncated, info = env.step(env.unwrapped.nominal_action())
print(obs.shape, reward)
```

One policy per agent: `pettingzoo.make("parallel", "{env_id}")` or
`rsvo_env.parallel_env("{scenario}")` (the same env; `safety_filter=False` turns the filter off);
many envs at once: `BatchedEnv("{scenario}", num_envs=...)` ([Many envs at once](../batched.md)).

## Parameters

Every one is a keyword of `gymnasium.make`, `rsvo_env.parallel_env` and `BatchedEnv`; an
unknown keyword raises `TypeError` naming it. What each means: [Scenarios](../scenarios.md).
The registered id's step limit is `max_steps`.

| keyword | default |
|---|---|
{rows}
"""


def gallery_page(ids: dict[str, str]) -> str:
    cards = "\n\n".join(
        f"-   **[`{env_id}`](scenarios/{scenario}.md)**\n\n"
        f"    ---\n\n"
        f"    [![{title(scenario)}](images/{scenario}.png)](scenarios/{scenario}.md)"
        for env_id, scenario in ids.items()
    )
    return f"""# Gallery

Every registered id, one episode of seed 0 under its scripted controller behind the filter: the
paths from the open circles (starts) to the crosses (goals), each agent's disc where it ended.
A click opens the id's page, with its animation and its parameters. Your own scene:
[custom scenes](scenarios.md#custom-scenes).

<div class="grid cards" markdown>

{cards}

</div>
"""


def write_pages() -> list[Path]:
    ids = registered()
    PAGES.mkdir(exist_ok=True)
    written = []
    for env_id, scenario in ids.items():
        path = PAGES / f"{scenario}.md"
        path.write_text(scenario_page(env_id, scenario))
        written.append(path)
    (DOCS / "gallery.md").write_text(gallery_page(ids))
    return [*written, DOCS / "gallery.md"]


def picture(scenario: str, name: str, **kwargs: object) -> None:
    """One episode of seed 0 as ``images/NAME.gif`` and ``images/NAME.png``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rsvo_env.cli.episode import run
    from rsvo_env.cli.figures import episode

    IMAGES.mkdir(exist_ok=True)
    # personalities spread over 1..10, so that the colours say who yields (the paper's point)
    kwargs = {"theta_range": (1.0, 10.0), **kwargs}
    out = run(scenario, gif=IMAGES / f"{name}.gif", gif_every=10, render_size=300, **kwargs)
    fig = episode(out, scenario, "asymmetric", filtered=True, legend="markers")
    fig.savefig(IMAGES / f"{name}.png", dpi=100, bbox_inches="tight")
    plt.close(fig)
    print(name, out["steps"], "steps,", out["n_collision_steps"], "collision steps")


def write_images() -> None:
    for scenario in registered().values():
        picture(scenario, scenario)
    write_model_images()


def write_model_images() -> None:
    for scenario, model in MODEL_SCENES:
        picture(scenario, f"{scenario}_{model}", dynamics=model)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pages", action="store_true", help="the pages alone, no pictures")
    ap.add_argument("--models", action="store_true", help="the MODEL_SCENES pictures alone")
    args = ap.parse_args()
    if args.models:
        write_model_images()
    else:
        for path in write_pages():
            print(path.relative_to(DOCS.parent))
    if not (args.pages or args.models):
        write_images()
