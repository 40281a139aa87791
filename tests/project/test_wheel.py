"""The wheel tested as users get it: built with the sdist, one top-level package with its type
marker, training configs and licence; installed into a fresh venv and run from a folder outside
the checkout: every id through ``gymnasium.make``, the filter alone, ``rsvo reproduce --quick``,
``rsvo --version``, and the old top-level names gone."""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

import rsvo_env

ROOT = Path(__file__).resolve().parents[2]

SMOKE = """
import importlib.util, pathlib, sys
import numpy as np, gymnasium
import rsvo_env
from rsvo_env import FilterConfig, SafetyFilter
from rsvo_env.envs.registration import IDS

checkout = pathlib.Path(sys.argv[1])
assert checkout not in pathlib.Path(rsvo_env.__file__).parents, rsvo_env.__file__
assert importlib.util.find_spec("wrappers") is None and importlib.util.find_spec("training") is None
import rsvo_env.wrappers, rsvo_env.training.config as config
assert (config.CONFIG_DIR / "crowd.yaml").is_file()
for env_id in IDS:
    env = gymnasium.make(env_id)
    env.reset(seed=0)
    for _ in range(3):
        env.step(env.unwrapped.nominal_action())
    venv = gymnasium.make_vec(env_id, 2, vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    venv.step(venv.action_space.sample())
flt = SafetyFilter(FilterConfig(gamma=5.0, safety_radius=1.0, u_max=1.0, dt=0.05))
x = np.array([[-0.51, 0.0], [0.51, 0.0]])
r = flt.filter(x, np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([1.0, 3.0]))
after = x + 0.05 * r.actions
assert r.feasible.all() and np.linalg.norm(after[0] - after[1]) >= 1.0, after
print("smoke ok", rsvo_env.__version__)
"""


def run(args: list[str], cwd: Path, timeout: int = 1200) -> subprocess.CompletedProcess:
    done = subprocess.run(args, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    assert done.returncode == 0, " ".join(args) + "\n" + done.stdout[-2000:] + done.stderr[-3000:]
    return done


@pytest.fixture(scope="module")
def dist(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("dist")
    run([sys.executable, "-m", "build", "--outdir", str(out), str(ROOT)], cwd=out)
    return out


def test_the_wheel_holds_one_package_its_marker_configs_and_licence(dist):
    (wheel,) = dist.glob("*.whl")
    (sdist,) = dist.glob("*.tar.gz")
    assert f"rsvo_env-{rsvo_env.__version__}" in wheel.name and rsvo_env.__version__ in sdist.name
    names = zipfile.ZipFile(wheel).namelist()
    top = {n.split("/")[0] for n in names}
    assert top == {"rsvo_env", f"rsvo_env-{rsvo_env.__version__}.dist-info"}, top
    for name in (
        "rsvo_env/py.typed",
        "rsvo_env/training/configs/crowd.yaml",
        "rsvo_env/wrappers/registered.py",
        "rsvo_env/training/train.py",
    ):
        assert name in names, name
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    assert not any("__pycache__" in n or n.endswith((".nbi", ".nbc")) for n in names)


def test_the_wheel_installed_in_a_fresh_venv_runs_from_outside_the_checkout(dist, tmp_path):
    (wheel,) = dist.glob("*.whl")
    venv = tmp_path / "venv"
    run([sys.executable, "-m", "venv", str(venv)], cwd=tmp_path)
    python, rsvo = venv / "bin" / "python", venv / "bin" / "rsvo"
    run([str(python), "-m", "pip", "install", "-q", str(wheel)], cwd=tmp_path)
    away = tmp_path / "elsewhere"
    away.mkdir()
    assert "smoke ok" in run([str(python), "-c", SMOKE, str(ROOT)], cwd=away).stdout
    assert run([str(rsvo), "--version"], cwd=away).stdout.strip() == f"rsvo {rsvo_env.__version__}"
    run([str(rsvo), "reproduce", "--quick", "--out", str(away / "results")], cwd=away)
    assert (away / "results" / "paper.md").is_file()
