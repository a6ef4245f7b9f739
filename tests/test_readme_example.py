"""The README's Python example runs as printed (STYLE: doc examples are run) and gives a σ.

Every Python block of ``README.md`` that makes a ``Catenary-`` environment is run in a fresh interpreter,
as a user would run it: so it also checks that ``import catenary_env`` registers the environments.
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("gymnasium", reason="the environments need gymnasium")

ROOT = Path(__file__).resolve().parents[1]
SOURCES = [ROOT / "README.md"]
BLOCK = re.compile(r"```python\n(.*?)```", re.DOTALL)


def examples() -> list[tuple[str, str]]:
    found = []
    for path in SOURCES:
        if path.exists():
            for i, code in enumerate(BLOCK.findall(path.read_text(encoding="utf-8"))):
                if 'gym.make("Catenary-' in code:
                    found.append((f"{path.name}#{i}", code))
    return found


def test_the_example_is_there() -> None:
    assert any(name.startswith("README.md") for name, _ in examples())


@pytest.mark.parametrize(("name", "code"), examples(), ids=[name for name, _ in examples()])
def test_example_runs_and_gives_a_sigma(name: str, code: str) -> None:
    check = "\nprint(repr(-reward), info['feasible'], info['std'])\n"
    result = subprocess.run(
        [sys.executable, "-c", code + check], capture_output=True, text=True, cwd=ROOT, timeout=600
    )
    assert result.returncode == 0, result.stderr
    minus_reward, feasible, sigma = result.stdout.split()[-3:]
    # Feasible or not, σ is a positive force; when feasible the reward is -σ.
    assert math.isfinite(float(sigma)) and float(sigma) > 0.0
    if feasible == "True":
        assert float(minus_reward) == float(sigma)
