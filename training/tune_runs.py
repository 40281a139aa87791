"""One way to run a Ray Tune experiment here: on a local Ray instance or a cluster, one CPU a
trial, results under ``out``, Ray shut down after, a failed trial raised."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any


def fit(
    trainable: Callable[[dict[str, Any]], None],
    param_space: dict[str, Any],
    tune_config: Any,
    name: str,
    out: str | Path,
    address: str | None = None,
) -> list[Any]:
    """Every trial's ``ray.tune.Result`` of the experiment ``name`` (``tune_config``: a
    ``tune.TuneConfig``); ``address``: a running cluster (None: a local instance)."""
    import ray
    from ray import tune

    ray.init(address=address, include_dashboard=False, log_to_driver=False)
    try:
        tuner = tune.Tuner(
            tune.with_resources(trainable, {"cpu": 1}),
            param_space=param_space,
            tune_config=tune_config,
            run_config=tune.RunConfig(name=name, storage_path=str(Path(out).resolve()), verbose=0),
        )
        results = list(tuner.fit())
    finally:
        ray.shutdown()
    for res in results:
        if res.error is not None:
            raise RuntimeError(f"a {name} trial failed: {res.error}")
    return results


def parse(parser: Any, argv: list[str] | None) -> Any:
    """The arguments of a Tune command, with ``--address`` (a running cluster) and ``--out``
    (a directory that can be written) added and checked."""
    from rsvo_env.util.arguments import output_problem

    parser.add_argument("--address", help="a running Ray cluster (default: a local instance)")
    parser.add_argument("--out", required=True)
    args = parser.parse_args(argv)
    problem = output_problem(Path(args.out), directory=True)
    if problem:
        parser.exit(2, f"{parser.prog}: error: --out {problem}\n")
    return args
