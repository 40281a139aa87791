"""The PettingZoo range: ``import rsvo_env`` and PettingZoo's own checkers at the oldest
supported release (1.24, without a registry; still pinned by clients such as AgileRL) as well as
at the installed newest one; an older PettingZoo is refused at import, naming both versions.

The old release is pip-installed (no dependencies: it is pure Python) into a folder that goes
first on the subprocess's path, so this venv is left as it is."""

import subprocess
import sys

import pytest

from tests.support.checkout import run_python

OLDEST = "1.24.3"
TOO_OLD = "1.23.1"

CHECKS = """
import warnings
warnings.simplefilter("ignore")
import pettingzoo, gymnasium
import rsvo_env
from rsvo_env.envs.registration import HAS_REGISTRY
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test, state_test
assert pettingzoo.__version__ == "{version}", pettingzoo.__version__
parallel_api_test(rsvo_env.parallel_env("crowd", num_agents=5), num_cycles=100)
api_test(rsvo_env.env("circular_swap", num_agents=4), num_cycles=100)
parallel_seed_test(lambda: rsvo_env.parallel_env("crowd", num_agents=5))
state_test(rsvo_env.env("crowd"), rsvo_env.parallel_env("crowd"), 50)
gymnasium.make("rsvo/Crowd-v0").reset(seed=0)  # gymnasium's ids whatever PettingZoo's version
print("registry", HAS_REGISTRY)
"""


def install(version, target):
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "-q",
            "--no-deps",
            "--target",
            str(target),
            f"pettingzoo=={version}",
        ],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return target


def run_with(target, code):
    # the old PettingZoo first, then the checkout (run_python puts the checkout first: put the
    # target before it by running through a tiny bootstrap)
    boot = f"import sys; sys.path.insert(0, {str(target)!r}); exec(compile({code!r}, 'c', 'exec'))"
    return run_python("-c", boot)


@pytest.fixture(scope="module")
def oldest(tmp_path_factory):
    return install(OLDEST, tmp_path_factory.mktemp("pz_oldest"))


def test_oldest_supported_pettingzoo_passes_its_own_checkers(oldest):
    done = run_with(oldest, CHECKS.format(version=OLDEST))
    assert done.returncode == 0, done.stderr[-3000:]
    assert "registry False" in done.stdout


def test_newest_installed_pettingzoo_passes_the_same_checks():
    import pettingzoo

    done = run_python("-c", CHECKS.format(version=pettingzoo.__version__))
    assert done.returncode == 0, done.stderr[-3000:]
    assert "registry True" in done.stdout


def test_too_old_pettingzoo_is_refused_naming_the_version(tmp_path):
    target = install(TOO_OLD, tmp_path)
    done = run_with(target, "import rsvo_env")
    assert done.returncode != 0
    assert f"found pettingzoo {TOO_OLD}" in done.stderr and "pettingzoo >= 1.24" in done.stderr


@pytest.mark.parametrize(
    "version, refused",
    [("1.24.0", False), ("1.27.0", False), ("2.0.0", False), ("1.23.1", True), ("0.9", True)],
)
def test_version_check(version, refused):
    from rsvo_env.envs.registration import check_pettingzoo

    if refused:
        with pytest.raises(ImportError, match=f"found pettingzoo {version}"):
            check_pettingzoo(version)
    else:
        check_pettingzoo(version)
